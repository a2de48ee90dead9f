//! Objects pressed into the finger: the seven built-in solids and loaded meshes.
