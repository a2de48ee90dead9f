//! The user-facing jobs, one module each, built on the library's sensor, render and localise
//! API (never on each other's internals): [`experiment`] reproduces the paper's
//! localisation experiment; [`dataset`] renders labelled synthetic datasets.
pub mod dataset;
pub mod experiment;
