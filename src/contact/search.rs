//! Rough search: candidate segment pairs from bounding boxes.
