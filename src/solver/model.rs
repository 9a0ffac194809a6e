//! The discrete model a Newton iteration sees: the bulk plus the interfaces.
//!
//! `F(u) = f_int(u) - f_ext(u, t) + f_tie(u) + f_contact(u)` and its tangent, assembled into
//! PETSc objects: each part adds its terms, then the vector or matrix is assembled once.

use crate::case::Scene;
use crate::contact::frictional::ContactInterfaces;
use crate::contact::tying::{Augmented, TiedInterfaces};
use crate::dofs::DofMap;
use crate::error::Result;
use crate::petsc::{Matrix, Vector};

use super::bulk::{Bulk, Inverted};

/// Bulk elements, tied and contact interfaces of this rank.
pub struct Model {
    pub bulk: Bulk,
    pub tying: TiedInterfaces,
    pub contact: ContactInterfaces,
}

/// Why a state cannot be evaluated: the step must be cut.
#[derive(Clone, Debug)]
pub enum DomainIssue {
    /// An element with a non-positive Jacobian determinant.
    Inverted(Inverted),
    /// A contact evaluation failed (a degenerate normal, a non-finite value).
    Contact(String),
}

/// The first issue found: an inverted element, else a contact failure.
fn first_issue(inv: Option<Inverted>, contact: Option<String>) -> Option<DomainIssue> {
    inv.map(DomainIssue::Inverted)
        .or(contact.map(DomainIssue::Contact))
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
    ) -> Result<Option<DomainIssue>> {
        f.set_all(0.0)?;
        let inv = self.bulk.add_residual(scene, dofs, u, t, f)?;
        self.tying.add_residual(dofs, u, f)?;
        let contact = self.contact.add_residual(scene, dofs, u, f)?;
        f.assemble()?;
        Ok(first_issue(inv, contact))
    }

    /// dF/du into `jac` (zeroed, assembled).
    pub fn jacobian(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        t: f64,
        jac: &mut Matrix,
    ) -> Result<Option<DomainIssue>> {
        jac.zero_entries()?;
        let inv = self.bulk.add_jacobian(scene, dofs, u, t, jac)?;
        self.tying.add_jacobian(dofs, jac)?;
        let contact = self.contact.add_jacobian(scene, dofs, u, jac)?;
        jac.assemble()?;
        Ok(first_issue(inv, contact))
    }

    /// This rank's `f_int - f_ext + f_tie + f_contact` at every dof (for reactions), into
    /// `out`.
    pub fn nodal_forces(&self, scene: &Scene, u: &[f64], t: f64, out: &mut [f64]) {
        self.bulk.nodal_forces(scene, u, t, out);
        self.tying.add_nodal_forces(u, out);
        self.contact.add_nodal_forces(scene, u, out);
    }

    /// One Uzawa step of every interface (collective): `Updated` if any multiplier changed,
    /// else `CapReached` if an interface is above its tolerance with no augmentations left,
    /// else `Converged`. Also returns the largest contact violation (a multiple of its
    /// tolerance).
    pub fn augment(
        &mut self,
        scene: &Scene,
        u: &[f64],
        done: usize,
        world: &mpi::topology::SimpleCommunicator,
    ) -> (Augmented, f64) {
        let tied = self.tying.augment(u, done, world);
        let (contact, violation) = self.contact.augment(scene, u, done, world);
        let result = if tied == Augmented::Updated || contact == Augmented::Updated {
            Augmented::Updated
        } else if tied == Augmented::CapReached || contact == Augmented::CapReached {
            Augmented::CapReached
        } else {
            Augmented::Converged
        };
        (result, violation)
    }
}
