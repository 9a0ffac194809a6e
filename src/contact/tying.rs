//! Mesh tying of dissimilar meshes.
