//! Input and output: Gmsh import, VTU/PVTU/PVD output, CSV history, summary, atomic writes,
//! PETSc's performance logs.

pub mod case_file;
pub mod checkpoint;
pub mod gmsh;
pub mod output;
pub mod petsc_log;
pub mod plot;
