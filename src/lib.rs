//! geltip: a simulator of the GelTip optical tactile sensor (Gomes, Lin, Luo: IROS 2020).
//!
//! The pipeline reads like the sensor: [`finger`] geometry and [`lens`] models make the
//! [`sensor`] projection map; the [`paper`] module keeps the paper's printed formula to
//! show where it goes wrong.
pub mod checks;
pub mod error;
pub mod finger;
pub mod lens;
pub mod paper;
pub mod sensor;

pub use error::{GeltipError, Result};
pub use finger::{Finger, Region, SurfaceCoord, SurfacePoint};
pub use lens::{Lens, LensModel};
pub use sensor::{NotVisible, Sensor, SensorConfig};
pub mod calibrate;
pub mod evaluate;
pub mod gpu;
pub mod host_speed;
pub mod jobs;
pub mod localise;
pub mod memory;
pub mod object;
pub mod output;
pub mod plot;
pub mod render;
pub mod scene;
pub mod view;
