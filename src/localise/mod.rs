//! Contact localisers: find contacts in tactile images and map them onto the finger.
