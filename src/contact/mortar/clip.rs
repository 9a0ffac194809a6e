//! Convex polygon clipping in the projection plane.
