//! Integration of one secondary face against one primary face.
