//! Input and output: Gmsh import, VTU/PVTU/PVD output, CSV history, summary, atomic writes.

pub mod case_file;
pub mod gmsh;
pub mod output;
pub mod plot;
