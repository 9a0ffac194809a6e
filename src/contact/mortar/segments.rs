//! Sub-segments of faces and traction shape functions.
