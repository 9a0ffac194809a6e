//! The discrete model a Newton iteration sees: the bulk plus the interfaces.
//!
//! `F(u) = f_int(u) - f_ext(u, t) + f_tie(u)` and its tangent, assembled into PETSc objects:
//! each part adds its terms, then the vector or matrix is assembled once.

use crate::case::Scene;
use crate::contact::tying::TiedInterfaces;
use crate::dofs::DofMap;
use crate::error::Result;
use crate::petsc::{Matrix, Vector};

use super::bulk::{Bulk, Inverted};

/// Bulk elements and tied interfaces of this rank.
pub struct Model {
    pub bulk: Bulk,
    pub tying: TiedInterfaces,
}

impl Model {
    /// F(u; t) into `f` (zeroed, assembled).
    pub fn residual(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        t: f64,
        f: &mut Vector,
    ) -> Result<Option<Inverted>> {
        f.set_all(0.0)?;
        let inv = self.bulk.add_residual(scene, dofs, u, t, f)?;
        self.tying.add_residual(dofs, u, f)?;
        f.assemble()?;
        Ok(inv)
    }

    /// dF/du into `jac` (zeroed, assembled).
    pub fn jacobian(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        t: f64,
        jac: &mut Matrix,
    ) -> Result<Option<Inverted>> {
        jac.zero_entries()?;
        let inv = self.bulk.add_jacobian(scene, dofs, u, t, jac)?;
        self.tying.add_jacobian(dofs, jac)?;
        jac.assemble()?;
        Ok(inv)
    }

    /// This rank's `f_int - f_ext + f_tie` at every dof (for reactions), into `out`.
    pub fn nodal_forces(&self, scene: &Scene, u: &[f64], t: f64, out: &mut [f64]) {
        self.bulk.nodal_forces(scene, u, t, out);
        self.tying.add_nodal_forces(u, out);
    }
}
