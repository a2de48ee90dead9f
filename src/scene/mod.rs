//! Contacts: what is pressed into the finger, where and how, and where that puts it.
//!
//! - [`spec`]: one contact as data ([`ContactSpec`]: the fields of the command line's
//!   flags, scene files and the Python package) checked into a [`Press`], and scene files.
//! - [`place`]: where on the finger ([`Place`]).
//! - [`hold`]: how an object is held ([`Hold`]): at a place or as a rigid pose.
//! - [`pose`]: an object held ([`Press`]) and the [`ContactPose`] it takes on a sensor's
//!   finger.
//! - [`first_touch`]: where an object brought towards the finger first touches it.
//!
//! The renderer takes contacts from here; [`crate::render`] re-exports the types its
//! callers name with it.

pub mod first_touch;
pub mod hold;
pub mod place;
pub mod pose;
pub mod spec;

pub use hold::{numbers, pose_numbers, Hold};
pub use place::{Place, PLACE_KEYS};
pub use pose::{ContactPose, Press};
pub use spec::{load_scene, naming_contact, presses, At, ContactSpec};
