//! The user-facing jobs, one module each, built on the library's sensor, render and localise
//! API (never on each other's internals): [`experiment`] reproduces the paper's
//! localisation experiment.
pub mod experiment;
pub mod preview;
pub mod stability;
pub mod tradeoff;
