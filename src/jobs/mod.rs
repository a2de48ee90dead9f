//! The user-facing jobs, one module each, built on the library's sensor, render and localise
//! API (never on each other's internals): [`experiment`] reproduces the paper's
//! localisation experiment; [`dataset`] renders labelled synthetic datasets; [`preview`]
//! shows what a sensor design sees; [`imprint`] fits the imprint's look to a real sensor's
//! contact frames; [`stability`] sweeps contacts to find where the
//! detectors fail; [`tradeoff`] measures the renderer's knobs for speed against accuracy.
pub mod calibrate;
pub mod dataset;
pub mod evaluate;
pub mod experiment;
pub mod imprint;
pub mod preview;
pub mod stability;
pub mod tradeoff;
