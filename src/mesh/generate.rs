//! Structured mesh generators, mesh merging and mesh validation.
//!
//! # Mapped blocks
//!
//! Every generator is built on [`mapped_block`]: a structured block over the unit parameter cube
//! `u = (u0, u1, u2) in [0, 1]^3` with `div = [n0, n1, n2]` cells, mapped to space by a
//! user-supplied `map: u -> x`. The nodes are the points of a lattice with `p n_d + 1` points
//! along direction `d`, where `p` is the element order (1 for Hex8/Tet4, 2 for the quadratic
//! types): lattice point `(i, j, k)` sits at `u = (i / (p n0), j / (p n1), k / (p n2))` and at
//! `x = map(u)`. **Every** node, mid-edge, face and centre nodes included, is mapped, so quadratic
//! elements reproduce a curved geometry (to interpolation accuracy) rather than being straight
//! sided. Only lattice points used by some element become mesh nodes (Hex20 uses no face or cell
//! centre points), numbered compactly in lattice order (`i` fastest, then `j`, then `k`).
//!
//! Cell `(a, b, c)` spans lattice points `p (a, b, c) .. p (a + 1, b + 1, c + 1)`.
//!
//! - **Hexahedra**: one element per cell with parametric axes `xi, eta, zeta` along `u0, u1, u2`;
//!   element node `k` with parametric coordinates `xi_k in {-1, 0, 1}^3` is lattice point
//!   `p (a, b, c) + p (xi_k + 1) / 2`.
//! - **Tetrahedra**: each cell is split into six tetrahedra along its main diagonal
//!   (Kuhn/Freudenthal split): for every permutation `s` of the three axes the tetrahedron
//!   `v0 = 0, v1 = e_s0, v2 = e_s0 + e_s1, v3 = (1, 1, 1)` (cell-local unit coordinates), with
//!   `v1, v2` swapped for odd permutations so that `det[v1 - v0, v2 - v0, v3 - v0] = +1`. The
//!   split is translation invariant, hence conforming across cells. A node with simplex
//!   coordinates `(xi, eta, zeta)` is the lattice point `p (a, b, c) + p (v0 + xi (v1 - v0) +
//!   eta (v2 - v0) + zeta (v3 - v0))`; the edges of the split are the seven directions `e_S`
//!   (`S` a non-empty subset of the axes), so Tet10 uses every point of the `2 n + 1` lattice.
//!
//! All elements have positive Jacobian determinant as long as `map` preserves orientation
//! (`det(dx/du) > 0`).
//!
//! Named sets: face sets and node sets `"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"` are the
//! sides `u0 = 0, u0 = 1, u1 = 0, ...` of the **parameter** cube (for [`box_mesh`] these are the
//! planes `x = lo[0]`, `x = hi[0]`, ...). A face belongs to a side when all its corners do.
//!
//! # Sphere octant
//!
//! [`thick_sphere_octant`] is a cube-sphere: three blocks, one per face `x = 1`, `y = 1`, `z = 1`
//! of the cube `[0, 1]^3`. On patch `x = 1` the surface parameters `(s, t)` give the cube point
//! `(1, tan(pi s / 4), tan(pi t / 4))` (equal-angle spacing), projected radially to
//! `r(w) = r_in + w (r_out - r_in)`; the other patches are its cyclic permutations, so all three
//! maps are orientation preserving. Coincident nodes of the patches are merged.
//!
//! # Graded boxes
//!
//! [`graded_box_mesh`] puts the cell corners along each axis at
//! `x = lo + (hi - lo) expm1(beta u) / expm1(beta)` ([`exp_grading`]), so the cells grow in a
//! constant ratio from `lo` to `hi` and the last is `grading` times the first
//! (`beta = ln(grading) n / (n - 1)` for `n` cells; OpenFOAM's expansion ratio);
//! [`zoned_box_mesh`] keeps the cells uniform over a zone at the fine end first
//! ([`ZoneGrading`]). Inside a cell the map is linear: the elements are straight-sided boxes,
//! with the mid-nodes of quadratic elements halfway along their edges.
//!
//! # Hemisphere
//!
//! [`hemisphere_quarter`] is the quarter `x, y >= 0` of a solid hemisphere of radius R, meant to
//! be pressed on something at its pole: a ball octant made of four mapped blocks, built in a
//! frame `(x', y', z')` with the centre at the origin and the pole on `+z'`:
//!
//! - the **core**: the cube `[0, c]^3`, `c = HEMISPHERE_CORE R`, mapped by
//!   `u -> c (tan(pi u0 / 4), tan(pi u1 / 4), tan(pi u2 / 4))`;
//! - three **shell patches**, one per cube face away from the centre (`x' = c`, `y' = c`,
//!   `z' = c`), as in the sphere octant: on patch `x'` the surface parameters `(s, t)` give the
//!   direction `d = (1, tan(pi s / 4), tan(pi t / 4))` (cyclic permutations for the other two),
//!   and the point at depth parameter `w` is `c d + omega(w) (R d / |d| - c d)`, from the cube
//!   face (where the core's lattice is, node for node) along the ray to the sphere. The layers
//!   are graded toward the sphere: the layer boundaries are at
//!   `omega(k / n_rad) = 1 - exp_grading(1 - k / n_rad, beta)` with the innermost layer
//!   `radial_grading` times as thick as the outermost, and `omega` is linear within a layer.
//!
//! The blocks meet node for node (the core's faces are the patches' inner faces, and
//! neighbouring patches share the rays of their common edge), and coincident nodes are merged.
//! Then every point goes through one **polar grading** map toward the pole, in spherical
//! coordinates about the centre (`theta` from the pole):
//! `theta -> theta + w(r) (G(theta) - theta)`, `r` and the azimuth kept, with the weight
//! `w(r) = (r / R)^2` (full at the surface, none at the centre) and `G` the [`ZoneGrading`] of
//! `[0, pi/2]` (uniform spacing over the arc `pole_zone` from the pole, then growing to
//! `pole_grading` times that at the equator) sampled at the `2 n_circ + 1` equal-angle polar
//! angles of the cell corners along a meridian and linear in between, so that within a cell
//! the map is a rotation by a linear function of the angle and the mid-nodes of quadratic
//! elements stay halfway (in angle) between their corners even where the cells grow fast.
//! (Exactly so on the symmetry-plane meridians, whose cell corners lie at those knots; inside
//! the polar patch a cell's corners are off the knots and may straddle one, so there the
//! mid-nodes are near halfway: the unit tests check every element's Jacobian at the gradings
//! used.) In
//! the `(r, theta)` plane its Jacobian determinant is `1 - w + w G'(theta) > 0`, so it is
//! orientation preserving; it keeps the sphere, the flat
//! face `theta = pi/2`, the symmetry planes (azimuth 0 and pi/2) and the axis, so sets and the
//! conformity of the blocks survive it. Grading the cube-sphere's surface parameters instead
//! (one monotone map on every parameter, which also keeps the patches conforming) would refine
//! toward the two symmetry planes all along them, not toward the pole alone; the polar map
//! refines a disc around the pole and coarsens toward the equator, with elements near the pole
//! about square (near the pole it scales the tangent plane uniformly).
//!
//! Last, `(x', y', z') -> (y', x', R - z')` (a proper rotation: two reflections) puts the pole
//! at the origin, the centre at `(0, 0, R)` and the flat face at `z = R`. Sets: `"sphere"`,
//! `"flat"`, `"symx"` (`x = 0`), `"symy"` (`y = 0`), from the parameter sides of the blocks. Every
//! map is orientation preserving; the elements with the smallest scaled Jacobian (about 0.2
//! with strong gradings) are in the shell where the three patches meet, as in any cube-sphere.
//!
//! # Validation
//!
//! [`Mesh::check`] verifies indices and element node counts and that
//! `det J = det(sum_a x_a (dN_a/dxi)^T)` is positive at every node of every element and at its
//! centre (`xi = 0` for hexahedra, `(1/4, 1/4, 1/4)` for tetrahedra).

use std::collections::{BTreeMap, HashMap};

use crate::error::{Error, Result};
use crate::fe::ElementType;
use crate::mesh::{FaceRef, Mesh};

/// Names of the six parameter-cube sides, in the order `(axis, min/max)`.
const SIDE_NAMES: [[&str; 2]; 3] = [["xmin", "xmax"], ["ymin", "ymax"], ["zmin", "zmax"]];

/// Element-local lattice offsets of every sub-element of one cell, in units of lattice steps.
fn cell_offsets(kind: ElementType) -> Vec<Vec<[usize; 3]>> {
    let p = kind.order() as f64;
    let ref_coords = kind.node_coords();
    let to_lattice = |x: [f64; 3]| -> [usize; 3] {
        let mut o = [0usize; 3];
        for d in 0..3 {
            o[d] = x[d].round() as usize;
        }
        o
    };
    if kind.is_hex() {
        vec![ref_coords
            .iter()
            .map(|xi| {
                to_lattice([
                    p * (xi[0] + 1.0) / 2.0,
                    p * (xi[1] + 1.0) / 2.0,
                    p * (xi[2] + 1.0) / 2.0,
                ])
            })
            .collect()]
    } else {
        const PERMS: [([usize; 3], bool); 6] = [
            ([0, 1, 2], false),
            ([1, 2, 0], false),
            ([2, 0, 1], false),
            ([0, 2, 1], true),
            ([2, 1, 0], true),
            ([1, 0, 2], true),
        ];
        PERMS
            .iter()
            .map(|&(s, odd)| {
                let mut v = [[0.0f64; 3]; 4];
                v[1][s[0]] = 1.0;
                v[2][s[0]] = 1.0;
                v[2][s[1]] = 1.0;
                v[3] = [1.0; 3];
                if odd {
                    v.swap(1, 2);
                }
                ref_coords
                    .iter()
                    .map(|xi| {
                        let mut x = [0.0; 3];
                        for d in 0..3 {
                            x[d] = p
                                * (v[0][d]
                                    + xi[0] * (v[1][d] - v[0][d])
                                    + xi[1] * (v[2][d] - v[0][d])
                                    + xi[2] * (v[3][d] - v[0][d]));
                        }
                        to_lattice(x)
                    })
                    .collect()
            })
            .collect()
    }
}

/// A structured block of `kind` elements over the unit parameter cube, mapped by `map`.
///
/// `div` is the number of cells per parameter direction; see the module documentation for the
/// lattice, the tetrahedral split and the named sets. All elements belong to body `body`.
///
/// # Panics
/// If a division is zero (validate user input before calling).
pub fn mapped_block(
    kind: ElementType,
    div: [usize; 3],
    map: impl Fn([f64; 3]) -> [f64; 3],
    body: &str,
) -> Mesh {
    assert!(
        div.iter().all(|&n| n > 0),
        "mapped_block: every division must be positive, got {div:?}"
    );
    let p = kind.order();
    let m = [p * div[0] + 1, p * div[1] + 1, p * div[2] + 1];
    let lin = |l: [usize; 3]| l[0] + m[0] * (l[1] + m[1] * l[2]);
    let offsets = cell_offsets(kind);

    // Elements as lattice points.
    let mut elems: Vec<Vec<[usize; 3]>> = Vec::new();
    for c in 0..div[2] {
        for b in 0..div[1] {
            for a in 0..div[0] {
                let base = [p * a, p * b, p * c];
                for sub in &offsets {
                    elems.push(
                        sub.iter()
                            .map(|o| [base[0] + o[0], base[1] + o[1], base[2] + o[2]])
                            .collect(),
                    );
                }
            }
        }
    }

    // Compact numbering of the used lattice points, in lattice order.
    let total = m[0] * m[1] * m[2];
    let mut id = vec![usize::MAX; total];
    for e in &elems {
        for &l in e {
            id[lin(l)] = 0;
        }
    }
    let mut mesh = Mesh::new();
    mesh.bodies.push(body.to_string());
    let mut node_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    let mut count = 0;
    for k in 0..m[2] {
        for j in 0..m[1] {
            for i in 0..m[0] {
                let l = [i, j, k];
                let li = lin(l);
                if id[li] == usize::MAX {
                    continue;
                }
                id[li] = count;
                let u = [
                    i as f64 / (m[0] - 1) as f64,
                    j as f64 / (m[1] - 1) as f64,
                    k as f64 / (m[2] - 1) as f64,
                ];
                mesh.coords.push(map(u));
                for d in 0..3 {
                    if l[d] == 0 {
                        node_sets
                            .entry(SIDE_NAMES[d][0].into())
                            .or_default()
                            .push(count);
                    }
                    if l[d] == m[d] - 1 {
                        node_sets
                            .entry(SIDE_NAMES[d][1].into())
                            .or_default()
                            .push(count);
                    }
                }
                count += 1;
            }
        }
    }

    let mut face_sets: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
    let nc_face = kind.face_type().num_corners();
    let mut nodes = Vec::with_capacity(kind.num_nodes());
    for e in &elems {
        nodes.clear();
        nodes.extend(e.iter().map(|&l| id[lin(l)]));
        let element = mesh.push_element(kind, 0, &nodes);
        for face in 0..kind.num_faces() {
            let corners = &kind.face_nodes(face)[..nc_face];
            for d in 0..3 {
                for (side, target) in [(0, 0), (1, m[d] - 1)] {
                    if corners.iter().all(|&c| e[c][d] == target) {
                        face_sets
                            .entry(SIDE_NAMES[d][side].into())
                            .or_default()
                            .push(FaceRef { element, face });
                    }
                }
            }
        }
    }
    for v in face_sets.values_mut() {
        v.sort_unstable();
    }
    mesh.node_sets = node_sets;
    mesh.face_sets = face_sets;
    mesh
}

/// A box `[lo, hi]` of `kind` elements with `div` cells per axis (affine [`mapped_block`]); the
/// sets `"xmin"`, ... are the planes `x = lo[0]`, ....
pub fn box_mesh(
    kind: ElementType,
    div: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
    body: &str,
) -> Mesh {
    graded_box_mesh(kind, div, lo, hi, [1.0; 3], body)
}

/// `expm1(beta u) / expm1(beta)`: a map of `[0, 1]` onto itself whose slope grows by the factor
/// `e^beta` from `u = 0` to `u = 1` (shrinks for `beta < 0`); the identity for `beta = 0`, and
/// exactly 0 and 1 at the ends.
pub fn exp_grading(u: f64, beta: f64) -> f64 {
    if beta == 0.0 {
        u
    } else if u <= 0.0 {
        0.0
    } else if u >= 1.0 {
        1.0
    } else {
        (beta * u).exp_m1() / beta.exp_m1()
    }
}

/// A smooth, increasing map of `[0, 1]` onto itself for graded meshes: the spacing of equal
/// parameter steps is uniform over a fine **zone** at the start (the first `zone` of the
/// image), then grows exponentially to `ratio` times the zone's at `u = 1`. With
/// `h(u) = 1` for `u <= u_z` and `exp(beta (u - u_z))` beyond, `beta = ln(ratio) / (1 - u_z)`,
/// the map is `H(u) / H(1)` with `H` the integral of `h` (continuous slope); `u_z` is solved
/// (bisection) so that `H(u_z) / H(1) = zone`. Without a zone it is [`exp_grading`] with
/// `beta = ln(ratio)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZoneGrading {
    u_zone: f64,
    beta: f64,
    total: f64,
}

impl ZoneGrading {
    /// `ratio >= 1` (1: the identity), `zone` in `[0, 1)`.
    ///
    /// # Panics
    /// If `ratio < 1` or `zone` is outside `[0, 1)` (validate user input first).
    pub fn new(ratio: f64, zone: f64) -> ZoneGrading {
        assert!(
            ratio >= 1.0 && ratio.is_finite() && (0.0..1.0).contains(&zone),
            "ZoneGrading: ratio {ratio} must be >= 1 and zone {zone} in [0, 1)"
        );
        let make = |u_zone: f64| {
            let beta = ratio.ln() / (1.0 - u_zone);
            let total = if beta == 0.0 {
                1.0
            } else {
                u_zone + (ratio - 1.0) / beta
            };
            ZoneGrading {
                u_zone,
                beta,
                total,
            }
        };
        if ratio == 1.0 || zone == 0.0 {
            return make(0.0);
        }
        // The zone's share of the image, u_z / H(1), grows from 0 to 1 with u_z.
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            let g = make(mid);
            if mid / g.total < zone {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        make(0.5 * (lo + hi))
    }

    /// The map at `u` (exactly 0 and 1 at the ends).
    pub fn map(&self, u: f64) -> f64 {
        if u <= 0.0 {
            return 0.0;
        }
        if u >= 1.0 {
            return 1.0;
        }
        if self.beta == 0.0 {
            return u;
        }
        let h = if u <= self.u_zone {
            u
        } else {
            self.u_zone + (self.beta * (u - self.u_zone)).exp_m1() / self.beta
        };
        h / self.total
    }
}

/// The exponent `beta` of [`exp_grading`] that makes `n` equal lattice cells map to cells
/// growing geometrically, the last `ratio` times as long as the first (0 for `n = 1` or
/// `ratio = 1`).
fn cell_ratio_exponent(ratio: f64, n: usize) -> f64 {
    if n < 2 || ratio == 1.0 {
        0.0
    } else {
        ratio.ln() * n as f64 / (n - 1) as f64
    }
}

/// A box `[lo, hi]` whose cells grow geometrically along each axis: along axis `d` the last
/// cell (at `hi[d]`) is `grading[d]` times as long as the first (at `lo[d]`), consecutive cells
/// in the constant ratio `grading[d]^(1 / (div[d] - 1))` (OpenFOAM's expansion ratio; 1 is
/// uniform, below 1 refines toward `hi`). The map per axis is
/// `x = lo + (hi - lo) expm1(beta u) / expm1(beta)` with `beta = ln(grading) n / (n - 1)`, smooth,
/// so the mid-nodes of quadratic elements follow it. Sets as [`box_mesh`].
///
/// # Panics
/// If a division is zero or a grading is not finite and positive (validate user input first).
pub fn graded_box_mesh(
    kind: ElementType,
    div: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
    grading: [f64; 3],
    body: &str,
) -> Mesh {
    zoned_box_mesh(kind, div, lo, hi, grading, [0.0; 3], body)
}

/// [`graded_box_mesh`] with a uniformly fine zone at the fine end of each axis (`lo` for a
/// grading above 1, `hi` below 1): along axis `d` the first `zone[d]` of the length (measured
/// from the fine end) has uniform cells, then the cells grow ([`ZoneGrading`]); the grading is
/// then the spacing at the coarse end over the zone's (the ratio of the continuous profile,
/// near that of the end cells). A zero zone is [`graded_box_mesh`]'s exact cell ratio. The cell
/// corners follow the map and every cell is straight (mid-nodes halfway along the edges).
///
/// # Panics
/// If a division is zero, a grading is not finite and positive, or a zone is not in
/// `[0, hi - lo)` (validate user input first).
pub fn zoned_box_mesh(
    kind: ElementType,
    div: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
    grading: [f64; 3],
    zone: [f64; 3],
    body: &str,
) -> Mesh {
    assert!(
        grading.iter().all(|g| g.is_finite() && *g > 0.0),
        "graded box: grading must be finite and positive, got {grading:?}"
    );
    // Per axis: (map, flipped) with the map refining toward u = 0.
    let axes: [(ZoneGrading, bool); 3] = std::array::from_fn(|d| {
        let (ratio, flip) = if grading[d] >= 1.0 {
            (grading[d], false)
        } else {
            (1.0 / grading[d], true)
        };
        let share = zone[d] / (hi[d] - lo[d]);
        assert!(
            (0.0..1.0).contains(&share),
            "graded box: zone {} outside the axis length",
            zone[d]
        );
        let g = if share == 0.0 {
            // The exact cell ratio: beta from the number of cells.
            let beta = cell_ratio_exponent(ratio, div[d]);
            ZoneGrading {
                u_zone: 0.0,
                beta,
                total: if beta == 0.0 {
                    1.0
                } else {
                    beta.exp_m1() / beta
                },
            }
        } else {
            ZoneGrading::new(ratio, share)
        };
        (g, flip)
    });
    // The cell corners along each axis; inside a cell the map is linear, so the elements are
    // straight-sided and the mid-nodes of quadratic elements sit at the middle of their edges
    // (the smooth map would push them toward the coarse end, by a lot in a steeply growing
    // cell).
    let corners: [Vec<f64>; 3] = std::array::from_fn(|d| {
        let (g, flip) = axes[d];
        (0..=div[d])
            .map(|i| {
                let u = i as f64 / div[d] as f64;
                if flip {
                    1.0 - g.map(1.0 - u)
                } else {
                    g.map(u)
                }
            })
            .collect()
    });
    let along = |d: usize, u: f64| -> f64 {
        let c = &corners[d];
        let t = u * div[d] as f64;
        let i = (t.floor() as usize).min(div[d] - 1);
        c[i] + (t - i as f64) * (c[i + 1] - c[i])
    };
    mapped_block(
        kind,
        div,
        |u| {
            [
                lo[0] + along(0, u[0]) * (hi[0] - lo[0]),
                lo[1] + along(1, u[1]) * (hi[1] - lo[1]),
                lo[2] + along(2, u[2]) * (hi[2] - lo[2]),
            ]
        },
        body,
    )
}

/// A beam along the x axis: the box `[0, length] x [-width/2, width/2] x [-height/2, height/2]`
/// (the beam axis is the x axis, the cross-section centred on it).
pub fn beam(
    kind: ElementType,
    div: [usize; 3],
    length: f64,
    width: f64,
    height: f64,
    body: &str,
) -> Mesh {
    box_mesh(
        kind,
        div,
        [0.0, -0.5 * width, -0.5 * height],
        [length, 0.5 * width, 0.5 * height],
        body,
    )
}

/// A boxed parameter-to-space map.
type PatchMap = Box<dyn Fn([f64; 3]) -> [f64; 3]>;

/// `tan(pi s / 4)`, exactly 1 at `s = 1` and 0 at `s = 0`.
fn tan_quarter(s: f64) -> f64 {
    if s >= 1.0 {
        1.0
    } else {
        (std::f64::consts::FRAC_PI_4 * s).tan()
    }
}

/// The octant `x, y, z >= 0` of the spherical shell `r_in <= r <= r_out` (cube-sphere, see the
/// module documentation): three patches of `n_circ x n_circ x n_rad` cells, one body.
///
/// Face and node sets: `"inner"` (`r = r_in`), `"outer"` (`r = r_out`), `"symx"` (`x = 0`),
/// `"symy"`, `"symz"`.
///
/// # Panics
/// If `n_circ` or `n_rad` is zero.
pub fn thick_sphere_octant(
    kind: ElementType,
    n_circ: usize,
    n_rad: usize,
    r_in: f64,
    r_out: f64,
    body: &str,
) -> Mesh {
    let radial = move |w: f64, d: [f64; 3]| -> [f64; 3] {
        let r = r_in + w * (r_out - r_in);
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        [r * d[0] / n, r * d[1] / n, r * d[2] / n]
    };
    let div = [n_circ, n_circ, n_rad];
    // (map, name of parameter side xmin, name of parameter side ymin)
    let patches: [(PatchMap, &str, &str); 3] = [
        (
            Box::new(move |u: [f64; 3]| radial(u[2], [1.0, tan_quarter(u[0]), tan_quarter(u[1])])),
            "symy",
            "symz",
        ),
        (
            Box::new(move |u: [f64; 3]| radial(u[2], [tan_quarter(u[1]), 1.0, tan_quarter(u[0])])),
            "symz",
            "symx",
        ),
        (
            Box::new(move |u: [f64; 3]| radial(u[2], [tan_quarter(u[0]), tan_quarter(u[1]), 1.0])),
            "symx",
            "symy",
        ),
    ];
    let mut out = Mesh::new();
    for (map, xmin, ymin) in patches {
        let mut patch = mapped_block(kind, div, map, body);
        let rename = [
            ("xmin", xmin),
            ("ymin", ymin),
            ("zmin", "inner"),
            ("zmax", "outer"),
        ];
        keep_sets_renamed(&mut patch, &rename);
        out.merge(patch);
    }
    out.merge_coincident_nodes(1e-6);
    out
}

/// Half-size of the core cube of [`hemisphere_quarter`], as a fraction of the radius.
pub const HEMISPHERE_CORE: f64 = 0.5;

/// A quarter of a solid hemisphere of radius `radius` (a ball octant), graded toward its pole
/// for contact: the pole at the origin, the centre at `(0, 0, radius)`, the flat (equatorial)
/// face at `z = radius`, and `x, y >= 0` (see the module documentation, "Hemisphere").
///
/// `n_circ` cells along each side of each of the three surface patches (and of the core cube),
/// `n_rad` through the shell between the core and the sphere; `pole_grading` (>= 1) is the ratio
/// of the polar-angle spacing at the equator to that at the pole on the spherical surface, and
/// `radial_grading` the ratio of the innermost shell layer's thickness to the outermost's (1:
/// uniform; above 1 the layers get thinner toward the surface).
///
/// Face and node sets: `"sphere"` (the spherical surface), `"flat"` (`z = radius`), `"symx"`
/// (`x = 0`), `"symy"` (`y = 0`).
///
/// # Panics
/// If `n_circ` or `n_rad` is zero, or a grading is not finite and positive.
#[allow(clippy::too_many_arguments)]
pub fn hemisphere_quarter(
    kind: ElementType,
    n_circ: usize,
    n_rad: usize,
    radius: f64,
    pole_grading: f64,
    pole_zone: f64,
    radial_grading: f64,
    body: &str,
) -> Mesh {
    assert!(
        pole_grading.is_finite()
            && pole_grading > 0.0
            && radial_grading.is_finite()
            && radial_grading > 0.0,
        "hemisphere_quarter: gradings must be finite and positive"
    );
    let r_big = radius;
    let core = HEMISPHERE_CORE * r_big;
    // Layers: the outermost is 1 / radial_grading of the innermost.
    let beta_rad = cell_ratio_exponent(radial_grading, n_rad);
    let half_pi = std::f64::consts::FRAC_PI_2;
    let smooth = ZoneGrading::new(pole_grading, pole_zone / (half_pi * r_big));
    // G at the polar angles of the cells' corners along a meridian (2 n_circ equal-angle cells
    // before grading), linear in between.
    let cells = 2 * n_circ;
    let polar = PolarGrading {
        identity: smooth.beta == 0.0,
        knots: (0..=cells)
            .map(|k| half_pi * smooth.map(k as f64 / cells as f64))
            .collect(),
    };
    // Everything is built in the frame (x', y', z') with the pole along +z' from the centre at
    // the origin, then turned by (x', y', z') -> (y', x', R - z') (two reflections: a proper
    // rotation plus a shift).
    let place = move |p: [f64; 3]| -> [f64; 3] {
        let q = polar_grading(p, r_big, &polar);
        [q[1], q[0], r_big - q[2]]
    };
    let place_core = place.clone();
    let layers: Vec<f64> = (0..=n_rad)
        .map(|k| 1.0 - exp_grading(1.0 - k as f64 / n_rad as f64, beta_rad))
        .collect();
    let shell = move |w: f64, d: [f64; 3]| -> [f64; 3] {
        // d has its largest component 1: core * d is on a face of the core cube, and the sphere
        // point on the same ray is R d / |d|.
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        // Thin layers at the surface: the layers' boundaries at 1 - grading(1 - k / n_rad),
        // linear within a layer (mid-nodes halfway through their layer).
        let t = (w * n_rad as f64).clamp(0.0, n_rad as f64);
        let k = (t.floor() as usize).min(n_rad - 1);
        let s = layers[k] + (t - k as f64) * (layers[k + 1] - layers[k]);
        let p: [f64; 3] = std::array::from_fn(|i| {
            let inner = core * d[i];
            let outer = r_big * d[i] / n;
            inner + s * (outer - inner)
        });
        place(p)
    };
    // (map, set names of the parameter sides xmin, ymin, zmin, zmax; "" for internal sides).
    // Final names: the plane x' = 0 becomes y = 0 ("symy") and y' = 0 becomes x = 0 ("symx");
    // z' = 0 is the flat face.
    let blocks: [(PatchMap, [&str; 4], [usize; 3]); 4] = [
        (
            Box::new(move |u: [f64; 3]| {
                place_core([
                    core * tan_quarter(u[0]),
                    core * tan_quarter(u[1]),
                    core * tan_quarter(u[2]),
                ])
            }),
            ["symy", "symx", "flat", ""],
            [n_circ, n_circ, n_circ],
        ),
        (
            Box::new({
                let shell = shell.clone();
                move |u: [f64; 3]| shell(u[2], [1.0, tan_quarter(u[0]), tan_quarter(u[1])])
            }),
            ["symx", "flat", "", "sphere"],
            [n_circ, n_circ, n_rad],
        ),
        (
            Box::new({
                let shell = shell.clone();
                move |u: [f64; 3]| shell(u[2], [tan_quarter(u[1]), 1.0, tan_quarter(u[0])])
            }),
            ["flat", "symy", "", "sphere"],
            [n_circ, n_circ, n_rad],
        ),
        (
            Box::new(move |u: [f64; 3]| shell(u[2], [tan_quarter(u[0]), tan_quarter(u[1]), 1.0])),
            ["symy", "symx", "", "sphere"],
            [n_circ, n_circ, n_rad],
        ),
    ];
    let mut out = Mesh::new();
    for (map, names, div) in blocks {
        let mut part = mapped_block(kind, div, map, body);
        let rename: Vec<(&str, &str)> = ["xmin", "ymin", "zmin", "zmax"]
            .into_iter()
            .zip(names)
            .filter(|(_, to)| !to.is_empty())
            .collect();
        keep_sets_renamed(&mut part, &rename);
        out.merge(part);
    }
    out.merge_coincident_nodes(1e-6);
    out
}

/// Keeps only the face and node sets named in `rename` (`(from, to)` pairs), under their new
/// names: a patch's box sets become the sets of the shape it is mapped to.
fn keep_sets_renamed(mesh: &mut Mesh, rename: &[(&str, &str)]) {
    mesh.face_sets = rename
        .iter()
        .filter_map(|(from, to)| mesh.face_sets.remove(*from).map(|v| (to.to_string(), v)))
        .collect();
    mesh.node_sets = rename
        .iter()
        .filter_map(|(from, to)| mesh.node_sets.remove(*from).map(|v| (to.to_string(), v)))
        .collect();
}

/// The polar grading of [`hemisphere_quarter`]: `G` at the equal-angle knots
/// `theta_k = k pi / (2 cells)`, `k = 0..=cells`.
#[derive(Clone)]
struct PolarGrading {
    identity: bool,
    knots: Vec<f64>,
}

impl PolarGrading {
    /// `G(theta)`, linear between the knots.
    fn at(&self, theta: f64) -> f64 {
        let cells = self.knots.len() - 1;
        let t = (theta / std::f64::consts::FRAC_PI_2 * cells as f64).clamp(0.0, cells as f64);
        let k = (t.floor() as usize).min(cells - 1);
        self.knots[k] + (t - k as f64) * (self.knots[k + 1] - self.knots[k])
    }
}

/// The grading of [`hemisphere_quarter`] toward its pole, in the frame with the pole along
/// `+z` from the centre at the origin: in spherical coordinates `(r, theta, phi)` about the
/// centre (`theta` from the pole), `theta -> theta + w (G(theta) - theta)` with `w = (r / R)^2`;
/// `r` and `phi` are kept. Points on the axis, on the plane `z = 0` or at the centre do not
/// move.
fn polar_grading(p: [f64; 3], radius: f64, polar: &PolarGrading) -> [f64; 3] {
    let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
    if polar.identity || rho == 0.0 || p[2] == 0.0 {
        return p;
    }
    let r = (rho * rho + p[2] * p[2]).sqrt();
    let theta = rho.atan2(p[2]);
    let g = polar.at(theta);
    let w = (r / radius).powi(2).min(1.0);
    let t = theta + w * (g - theta);
    let (sin, cos) = t.sin_cos();
    [p[0] * r * sin / rho, p[1] * r * sin / rho, r * cos]
}

/// Sorts and removes duplicates.
fn sort_dedup<T: Ord>(v: &mut Vec<T>) {
    v.sort_unstable();
    v.dedup();
}

impl Mesh {
    /// Appends `other`: its nodes and elements follow this mesh's, bodies are matched by name
    /// (new names appended), and named sets of the same name are united. Nodes are not shared;
    /// see [`Mesh::merge_coincident_nodes`].
    pub fn merge(&mut self, other: Mesh) {
        let n0 = self.num_nodes();
        let e0 = self.num_elements();
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        let body_map: Vec<usize> = other
            .bodies
            .iter()
            .map(|name| match self.bodies.iter().position(|b| b == name) {
                Some(i) => i,
                None => {
                    self.bodies.push(name.clone());
                    self.bodies.len() - 1
                }
            })
            .collect();
        self.coords.extend_from_slice(&other.coords);
        for e in 0..other.num_elements() {
            let nodes: Vec<usize> = other.element_nodes(e).iter().map(|&n| n + n0).collect();
            self.push_element(other.types[e], body_map[other.body[e]], &nodes);
        }
        for (name, nodes) in other.node_sets {
            let v = self.node_sets.entry(name).or_default();
            v.extend(nodes.into_iter().map(|n| n + n0));
            sort_dedup(v);
        }
        for (name, faces) in other.face_sets {
            let v = self.face_sets.entry(name).or_default();
            v.extend(faces.into_iter().map(|f| FaceRef {
                element: f.element + e0,
                face: f.face,
            }));
            sort_dedup(v);
        }
        for (name, elems) in other.element_sets {
            let v = self.element_sets.entry(name).or_default();
            v.extend(elems.into_iter().map(|e| e + e0));
            sort_dedup(v);
        }
    }

    /// Shortest corner-to-corner element edge, or the bounding-box diagonal if there are no
    /// elements (0 for an empty mesh).
    fn min_edge_length(&self) -> f64 {
        let dist = |a: [f64; 3], b: [f64; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        let mut h = f64::INFINITY;
        for e in 0..self.num_elements() {
            let en = self.element_nodes(e);
            for ed in self.types[e].edges() {
                h = h.min(dist(self.coords[en[ed[0]]], self.coords[en[ed[1]]]));
            }
        }
        if h.is_finite() {
            return h;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for x in &self.coords {
            for d in 0..3 {
                lo[d] = lo[d].min(x[d]);
                hi[d] = hi[d].max(x[d]);
            }
        }
        if self.coords.is_empty() {
            0.0
        } else {
            dist(lo, hi)
        }
    }

    /// Merges nodes closer than `tol * h`, `h` the shortest element edge (so `tol < 0.5` never
    /// merges two nodes of one element), keeping the first node of each cluster. Nodes are
    /// renumbered compactly in their original order; connectivity and node sets follow.
    pub fn merge_coincident_nodes(&mut self, tol: f64) {
        let abs_tol = tol * self.min_edge_length();
        if self.coords.is_empty() || abs_tol <= 0.0 || !abs_tol.is_finite() {
            return;
        }
        // Spatial hash with cells of size abs_tol: close nodes are in neighbouring cells.
        let cell = |x: [f64; 3]| -> [i64; 3] {
            [
                (x[0] / abs_tol).floor() as i64,
                (x[1] / abs_tol).floor() as i64,
                (x[2] / abs_tol).floor() as i64,
            ]
        };
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        let n = self.num_nodes();
        let mut new_id = vec![0usize; n];
        let mut kept: Vec<[f64; 3]> = Vec::with_capacity(n);
        for (i, &x) in self.coords.iter().enumerate() {
            let c = cell(x);
            let mut found = None;
            'search: for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                            for &k in list {
                                let y = kept[k];
                                let d2 = (x[0] - y[0]).powi(2)
                                    + (x[1] - y[1]).powi(2)
                                    + (x[2] - y[2]).powi(2);
                                if d2 <= abs_tol * abs_tol {
                                    found = Some(k);
                                    break 'search;
                                }
                            }
                        }
                    }
                }
            }
            new_id[i] = match found {
                Some(k) => k,
                None => {
                    kept.push(x);
                    grid.entry(c).or_default().push(kept.len() - 1);
                    kept.len() - 1
                }
            };
        }
        self.coords = kept;
        for c in &mut self.conn {
            *c = new_id[*c];
        }
        for v in self.node_sets.values_mut() {
            for c in v.iter_mut() {
                *c = new_id[*c];
            }
            sort_dedup(v);
        }
    }

    /// Describes element `e` for messages: `element 17 (hex8, body 'top')`.
    fn describe_element(&self, e: usize, label: &dyn Fn(usize) -> String) -> String {
        let body = self
            .body
            .get(e)
            .and_then(|&b| self.bodies.get(b))
            .map(|s| s.as_str())
            .unwrap_or("?");
        format!("{} ({}, body '{body}')", label(e), self.types[e].name())
    }

    /// Elements that share an edge (its two corner nodes) share its nodes, the same mid-edge
    /// node or none, and quadrilateral faces that share their corners share their centre node
    /// or have none: a linear element against a quadratic one (Hex8 against Hex20, Tet4 against
    /// Tet10), a Hex20 face against a Hex27 one, or quadratic elements whose mid-edge nodes were
    /// not merged would leave a crack in the body. (A ring of quadratic elements only two
    /// around, whose two edges join the same corners, would be refused too.) Only meshes with
    /// quadratic elements are checked (linear ones have nothing to disagree on), and faces
    /// only with Hex27 among them.
    fn check_conforming(&self, label: &dyn Fn(usize) -> String) -> Result<()> {
        if self.types.iter().all(|t| t.order() == 1) {
            return Ok(());
        }
        let with_centres = self.types.contains(&ElementType::Hex27);
        let mismatch = |e: usize, other: usize, what: String| {
            Error::Mesh(format!(
                "{} and {} share {what} but not its nodes (mixed element orders or unmerged \
                 nodes: the mesh would crack there)",
                self.describe_element(other, label),
                self.describe_element(e, label)
            ))
        };
        let mut edges: HashMap<(usize, usize), (usize, Option<usize>)> = HashMap::new();
        let mut faces: HashMap<[usize; 4], (usize, Option<usize>)> = HashMap::new();
        for e in 0..self.num_elements() {
            let kind = self.types[e];
            let en = self.element_nodes(e);
            for (k, &[a, b]) in kind.edges().iter().enumerate() {
                let key = (en[a].min(en[b]), en[a].max(en[b]));
                let mid = (kind.order() == 2).then(|| en[kind.num_corners() + k]);
                let (other, theirs) = *edges.entry(key).or_insert((e, mid));
                if theirs != mid {
                    let what = format!("the edge between nodes {} and {}", key.0, key.1);
                    return Err(mismatch(e, other, what));
                }
            }
            if with_centres && kind.is_hex() {
                for f in 0..kind.num_faces() {
                    let nodes = kind.face_nodes(f);
                    let mut key = [en[nodes[0]], en[nodes[1]], en[nodes[2]], en[nodes[3]]];
                    key.sort_unstable();
                    let centre = (kind == ElementType::Hex27).then(|| en[20 + f]);
                    let (other, theirs) = *faces.entry(key).or_insert((e, centre));
                    if theirs != centre {
                        let what = format!("the face with corner nodes {key:?}");
                        return Err(mismatch(e, other, what));
                    }
                }
            }
        }
        Ok(())
    }

    /// Validates the mesh: array lengths, connectivity indices, element node counts, body and
    /// set indices, finite coordinates, conforming elements (shared edges and faces share
    /// their nodes), and a positive Jacobian determinant at every node and the centre of every
    /// element. Element indices in messages are 0-based.
    pub fn check(&self) -> Result<()> {
        self.check_labelled(&|e| format!("element {e}"))
    }

    /// [`Mesh::check`] with elements named by `label(e)` (e.g. with their Gmsh tags).
    pub(crate) fn check_labelled(&self, label: &dyn Fn(usize) -> String) -> Result<()> {
        let ne = self.num_elements();
        let nn = self.num_nodes();
        if self.offsets.len() != ne + 1 || self.body.len() != ne {
            return Err(Error::Mesh(format!(
                "inconsistent arrays: {ne} element types, {} bodies of elements, {} offsets",
                self.body.len(),
                self.offsets.len()
            )));
        }
        if self.offsets[0] != 0 || *self.offsets.last().unwrap_or(&0) != self.conn.len() {
            return Err(Error::Mesh(format!(
                "offsets must run from 0 to the connectivity length {}",
                self.conn.len()
            )));
        }
        for (i, x) in self.coords.iter().enumerate() {
            if !x.iter().all(|&v| crate::within_bounds(v)) {
                return Err(Error::Mesh(format!(
                    "node {i} has coordinates {x:?}: not finite or beyond +-{:e}",
                    crate::MAX_MAGNITUDE
                )));
            }
        }
        for e in 0..ne {
            let (a, b) = (self.offsets[e], self.offsets[e + 1]);
            if b < a || b > self.conn.len() {
                return Err(Error::Mesh(format!(
                    "element {e}: bad connectivity offsets {a}..{b}"
                )));
            }
            if self.body[e] >= self.bodies.len() {
                return Err(Error::Mesh(format!(
                    "{} ({}) has body index {} but there are {} bodies",
                    label(e),
                    self.types[e].name(),
                    self.body[e],
                    self.bodies.len()
                )));
            }
            let kind = self.types[e];
            if b - a != kind.num_nodes() {
                return Err(Error::Mesh(format!(
                    "{} has {} nodes, expected {}",
                    self.describe_element(e, label),
                    b - a,
                    kind.num_nodes()
                )));
            }
            for (k, &n) in self.element_nodes(e).iter().enumerate() {
                if n >= nn {
                    return Err(Error::Mesh(format!(
                        "{}: its node {k} is node {n}, but the mesh has {nn} nodes",
                        self.describe_element(e, label)
                    )));
                }
            }
        }
        for (name, v) in &self.node_sets {
            if let Some(&n) = v.iter().find(|&&n| n >= nn) {
                return Err(Error::Mesh(format!(
                    "node set '{name}' contains node {n}, but the mesh has {nn} nodes"
                )));
            }
        }
        for (name, v) in &self.element_sets {
            if let Some(&e) = v.iter().find(|&&e| e >= ne) {
                return Err(Error::Mesh(format!(
                    "element set '{name}' contains element {e}, but the mesh has {ne} elements"
                )));
            }
        }
        for (name, v) in &self.face_sets {
            for f in v {
                if f.element >= ne {
                    return Err(Error::Mesh(format!(
                        "face set '{name}' refers to element {}, but the mesh has {ne} elements",
                        f.element
                    )));
                }
                if f.face >= self.types[f.element].num_faces() {
                    return Err(Error::Mesh(format!(
                        "face set '{name}' refers to face {} of {}, which has {} faces",
                        f.face,
                        self.describe_element(f.element, label),
                        self.types[f.element].num_faces()
                    )));
                }
            }
        }
        self.check_conforming(label)?;
        // Jacobians at the nodes and the centre.
        let mut dn = vec![[0.0; 3]; 27];
        let mut points: HashMap<ElementType, Vec<[f64; 3]>> = HashMap::new();
        for e in 0..ne {
            let kind = self.types[e];
            let pts = points.entry(kind).or_insert_with(|| {
                let mut p = kind.node_coords();
                p.push(if kind.is_hex() { [0.0; 3] } else { [0.25; 3] });
                p
            });
            let en = self.element_nodes(e);
            let dn = &mut dn[..kind.num_nodes()];
            for (k, &xi) in pts.iter().enumerate() {
                kind.shape_grad(xi, dn);
                let mut j = [[0.0; 3]; 3];
                for (a, &n) in en.iter().enumerate() {
                    let x = self.coords[n];
                    for r in 0..3 {
                        for c in 0..3 {
                            j[r][c] += x[r] * dn[a][c];
                        }
                    }
                }
                let det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
                    - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
                    + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
                if det.is_nan() || det <= 0.0 {
                    let at = if k < kind.num_nodes() {
                        format!("its node {k} (mesh node {})", en[k])
                    } else {
                        "its centre".to_string()
                    };
                    return Err(Error::Mesh(format!(
                        "{} is inverted: det J = {det:e} at {at}",
                        self.describe_element(e, label)
                    )));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two elements of a `kind` box sharing a face, the first cut down to its first `keep`
    /// nodes and made a `first` (Hex27 -> Hex20 -> Hex8 keep the leading nodes, VTK's order).
    fn two_with_first_as(kind: ElementType, first: ElementType) -> Mesh {
        let mut m = box_mesh(kind, [2, 1, 1], [0.0; 3], [2.0, 1.0, 1.0], "b");
        let keep = first.num_nodes();
        let mut conn = m.element_nodes(0)[..keep].to_vec();
        conn.extend_from_slice(m.element_nodes(1));
        m.types[0] = first;
        m.offsets = vec![0, keep, conn.len()];
        m.conn = conn;
        m
    }

    #[test]
    fn elements_of_mixed_orders_sharing_nodes_are_refused() {
        let e = two_with_first_as(ElementType::Hex20, ElementType::Hex8)
            .check()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("element 0 (hex8") && e.contains("element 1 (hex20") && e.contains("edge"),
            "{e}"
        );
        // The same edges, but a face with a centre node on one side only.
        let e = two_with_first_as(ElementType::Hex27, ElementType::Hex20)
            .check()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("hex20") && e.contains("hex27") && e.contains("face"),
            "{e}"
        );
        // The control: both kept whole.
        two_with_first_as(ElementType::Hex27, ElementType::Hex27)
            .check()
            .unwrap();
    }

    const ALL: [ElementType; 5] = ElementType::ALL;

    /// Volume of the mesh by quadrature of det J (degree 6).
    pub(super) fn volume(m: &Mesh) -> f64 {
        let mut v = 0.0;
        for e in 0..m.num_elements() {
            let kind = m.types[e];
            let rule = kind.quadrature(6);
            let x = m.element_coords(e);
            let mut dn = vec![[0.0; 3]; kind.num_nodes()];
            for (p, w) in rule.points.iter().zip(&rule.weights) {
                kind.shape_grad(*p, &mut dn);
                let mut j = [[0.0; 3]; 3];
                for a in 0..x.len() {
                    for r in 0..3 {
                        for c in 0..3 {
                            j[r][c] += x[a][r] * dn[a][c];
                        }
                    }
                }
                let det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
                    - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
                    + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
                v += w * det;
            }
        }
        v
    }

    fn expected_nodes(kind: ElementType, n: [usize; 3]) -> usize {
        let q = |d: usize| 2 * n[d] + 1;
        let l = |d: usize| n[d] + 1;
        match kind {
            ElementType::Hex8 | ElementType::Tet4 => l(0) * l(1) * l(2),
            ElementType::Hex27 | ElementType::Tet10 => q(0) * q(1) * q(2),
            ElementType::Hex20 => {
                l(0) * l(1) * l(2) + n[0] * l(1) * l(2) + l(0) * n[1] * l(2) + l(0) * l(1) * n[2]
            }
        }
    }

    #[test]
    fn boxes_of_every_type() {
        let div = [3, 2, 4];
        let (lo, hi) = ([-1.0, 0.5, 2.0], [2.0, 1.5, 2.5]);
        for kind in ALL {
            let m = box_mesh(kind, div, lo, hi, "b");
            m.check().unwrap();
            let per_cell = if kind.is_hex() { 1 } else { 6 };
            assert_eq!(m.num_elements(), 24 * per_cell);
            assert_eq!(m.num_nodes(), expected_nodes(kind, div), "{kind:?}");
            // Every node is used.
            let mut used = vec![false; m.num_nodes()];
            for &n in &m.conn {
                used[n] = true;
            }
            assert!(used.iter().all(|&u| u), "{kind:?}");
            assert!((volume(&m) - 3.0 * 1.0 * 0.5).abs() < 1e-12, "{kind:?}");
            let faces_per_cell = if kind.is_hex() { 1 } else { 2 };
            for (d, names) in SIDE_NAMES.iter().enumerate() {
                let ncells = div[(d + 1) % 3] * div[(d + 2) % 3];
                for (side, name) in names.iter().enumerate() {
                    let plane = if side == 0 { lo[d] } else { hi[d] };
                    let fs = m.face_set(name).unwrap();
                    assert_eq!(fs.len(), ncells * faces_per_cell, "{kind:?} {name}");
                    for &f in fs {
                        for n in m.face_nodes(f) {
                            assert!((m.coords[n][d] - plane).abs() < 1e-14);
                        }
                    }
                    let ns = m.node_set(name).unwrap();
                    let on_plane = (0..m.num_nodes())
                        .filter(|&n| (m.coords[n][d] - plane).abs() < 1e-14)
                        .count();
                    assert_eq!(ns.len(), on_plane, "{kind:?} {name}");
                    assert_eq!(m.nodes_of_set(name).unwrap().len(), on_plane);
                }
            }
        }
    }

    #[test]
    fn beam_is_centred_on_the_x_axis() {
        let m = beam(ElementType::Hex20, [4, 1, 2], 10.0, 1.0, 2.0, "beam");
        m.check().unwrap();
        assert!((volume(&m) - 20.0).abs() < 1e-11);
        for &n in m.node_set("xmin").unwrap() {
            assert_eq!(m.coords[n][0], 0.0);
        }
        for &n in m.node_set("zmax").unwrap() {
            assert_eq!(m.coords[n][2], 1.0);
        }
    }

    #[test]
    fn sphere_octant_of_every_type() {
        let (r_in, r_out): (f64, f64) = (1.0, 1.5);
        let exact = std::f64::consts::PI / 6.0 * (r_out.powi(3) - r_in.powi(3));
        for kind in ALL {
            let (nc, nr) = (3, 2);
            let m = thick_sphere_octant(kind, nc, nr, r_in, r_out, "shell");
            m.check().unwrap();
            assert_eq!(m.bodies, vec!["shell".to_string()]);
            // Three patches sharing three quarter-discs (radial faces), merged.
            let p = kind.order();
            let one = expected_nodes(kind, [nc, nc, nr]);
            let shared = if kind == ElementType::Hex20 {
                // A shared radial face of the lattice has (p nc + 1) x (p nr + 1) points minus the
                // unused face centres nc * nr.
                (p * nc + 1) * (p * nr + 1) - nc * nr
            } else {
                (p * nc + 1) * (p * nr + 1)
            };
            let axis = p * nr + 1; // the line x = y = z, shared by all three
            assert_eq!(m.num_nodes(), 3 * one - 3 * shared + axis, "{kind:?}");
            let per_cell = if kind.is_hex() { 1 } else { 6 };
            assert_eq!(m.num_elements(), 3 * nc * nc * nr * per_cell);
            let rel = (volume(&m) - exact).abs() / exact;
            let tol = if p == 1 { 0.05 } else { 2e-3 };
            assert!(rel < tol, "{kind:?}: volume error {rel}");
            let r = |n: usize| {
                let x = m.coords[n];
                (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
            };
            let fpc = if kind.is_hex() { 1 } else { 2 };
            for (name, radius) in [("inner", r_in), ("outer", r_out)] {
                assert_eq!(m.face_set(name).unwrap().len(), 3 * nc * nc * fpc);
                for n in m.nodes_of_set(name).unwrap() {
                    assert!((r(n) - radius).abs() < 1e-13, "{kind:?} {name}");
                }
                let all = (0..m.num_nodes())
                    .filter(|&n| (r(n) - radius).abs() < 1e-9)
                    .count();
                assert_eq!(m.node_set(name).unwrap().len(), all);
            }
            for (d, name) in ["symx", "symy", "symz"].iter().enumerate() {
                assert_eq!(
                    m.face_set(name).unwrap().len(),
                    2 * nc * nr * fpc,
                    "{kind:?}"
                );
                for n in m.nodes_of_set(name).unwrap() {
                    assert_eq!(m.coords[n][d], 0.0);
                }
                let all = (0..m.num_nodes())
                    .filter(|&n| m.coords[n][d] == 0.0)
                    .count();
                assert_eq!(m.node_set(name).unwrap().len(), all, "{kind:?} {name}");
            }
            // Every face is shared by at most two elements, and the boundary is exactly the
            // five named face sets: the merge left no internal seams.
            let (xadj, _) = crate::mesh::partition::dual_graph(&m);
            let nf = m.types[0].num_faces();
            let boundary = m.num_elements() * nf - xadj[m.num_elements()];
            let named: usize = ["inner", "outer", "symx", "symy", "symz"]
                .iter()
                .map(|s| m.face_sets[*s].len())
                .sum();
            assert_eq!(boundary, named, "{kind:?}");
        }
    }

    #[test]
    fn graded_box_cells_grow_geometrically() {
        for kind in [ElementType::Hex8, ElementType::Hex27, ElementType::Tet10] {
            let (lo, hi) = ([0.0, -1.0, -2.0], [1.0, 1.0, 0.0]);
            let m = graded_box_mesh(kind, [4, 3, 5], lo, hi, [8.0, 1.0, 0.1], "b");
            m.check().unwrap();
            assert!((volume(&m) - 4.0).abs() < 1e-12, "{kind:?}");
            // The corner (vertex) coordinates along each axis.
            let p = kind.order();
            let mut xs: Vec<f64> = m
                .node_set("ymin")
                .unwrap()
                .iter()
                .map(|&n| m.coords[n][0])
                .collect();
            xs.sort_by(f64::total_cmp);
            xs.dedup();
            assert_eq!(xs.len(), 4 * p + 1);
            let cells: Vec<f64> = (0..4).map(|i| xs[p * (i + 1)] - xs[p * i]).collect();
            let q = 8f64.powf(1.0 / 3.0);
            for w in cells.windows(2) {
                assert!((w[1] / w[0] - q).abs() < 1e-12, "{cells:?}");
            }
            assert!((cells[3] / cells[0] - 8.0).abs() < 1e-11);
            let mut zs: Vec<f64> = m
                .node_set("xmin")
                .unwrap()
                .iter()
                .map(|&n| m.coords[n][2])
                .collect();
            zs.sort_by(f64::total_cmp);
            zs.dedup();
            let first = zs[p] - zs[0];
            let last = zs[5 * p] - zs[5 * p - p];
            assert!((last / first - 0.1).abs() < 1e-12);
            assert_eq!(zs[0], -2.0);
            assert_eq!(zs[5 * p], 0.0);
            // Uniform along y.
            let mut ys: Vec<f64> = m
                .node_set("xmin")
                .unwrap()
                .iter()
                .map(|&n| m.coords[n][1])
                .collect();
            ys.sort_by(f64::total_cmp);
            ys.dedup();
            for (i, y) in ys.iter().enumerate() {
                assert!((y - (-1.0 + 2.0 * i as f64 / (3 * p) as f64)).abs() < 1e-14);
            }
        }
        // Grading 1 is the plain box, bit for bit.
        let a = box_mesh(
            ElementType::Hex20,
            [2, 3, 4],
            [0.0; 3],
            [1.0, 2.0, 3.0],
            "b",
        );
        let b = graded_box_mesh(
            ElementType::Hex20,
            [2, 3, 4],
            [0.0; 3],
            [1.0, 2.0, 3.0],
            [1.0; 3],
            "b",
        );
        assert_eq!(a.coords, b.coords);
    }

    #[test]
    fn zone_grading_is_uniform_in_its_zone_then_grows_to_its_ratio() {
        for (ratio, zone) in [(1.0, 0.0), (1.0, 0.5), (20.0, 0.0), (20.0, 0.3), (5.0, 0.8)] {
            let g = ZoneGrading::new(ratio, zone);
            assert_eq!(g.map(0.0), 0.0);
            assert_eq!(g.map(1.0), 1.0);
            let n = 2000;
            let x: Vec<f64> = (0..=n).map(|i| g.map(i as f64 / n as f64)).collect();
            let dx: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
            assert!(
                dx.iter().all(|&d| d > 0.0),
                "{ratio} {zone}: not increasing"
            );
            // Slopes: the end over the start is the ratio.
            let end = dx[n - 1] / dx[0];
            assert!((end - ratio).abs() < 0.01 * ratio, "{ratio} {zone}: {end}");
            // Uniform over the first `zone` of the image, growing after it.
            let in_zone: Vec<f64> = dx
                .iter()
                .zip(&x)
                .filter(|(_, &xi)| xi < zone - 1e-3)
                .map(|(d, _)| *d)
                .collect();
            if let (Some(lo), Some(hi)) = (
                in_zone.iter().cloned().reduce(f64::min),
                in_zone.iter().cloned().reduce(f64::max),
            ) {
                assert!((hi - lo).abs() < 1e-9 * hi, "{ratio} {zone}");
                if ratio > 1.0 {
                    let after = dx[in_zone.len() + 10];
                    assert!(after > hi * (1.0 + 1e-6), "{ratio} {zone}");
                }
            }
        }
        // Without a zone, the exponential map.
        let g = ZoneGrading::new(8.0, 0.0);
        for u in [0.1, 0.5, 0.9] {
            assert!((g.map(u) - exp_grading(u, 8f64.ln())).abs() < 1e-14);
        }
    }

    #[test]
    fn zoned_box_keeps_uniform_cells_near_its_fine_end() {
        let m = zoned_box_mesh(
            ElementType::Hex8,
            [10, 2, 10],
            [0.0, 0.0, -1.0],
            [1.0, 1.0, 0.0],
            [10.0, 1.0, 0.1],
            [0.3, 0.0, 0.3],
            "b",
        );
        m.check().unwrap();
        assert!((volume(&m) - 1.0).abs() < 1e-12);
        let coords = |set: &str, d: usize| {
            let mut v: Vec<f64> = m
                .node_set(set)
                .unwrap()
                .iter()
                .map(|&n| m.coords[n][d])
                .collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        };
        // x from 0: equal cells up to 0.3, growing after.
        let xs = coords("ymin", 0);
        let cells: Vec<f64> = xs.windows(2).map(|w| w[1] - w[0]).collect();
        let k = xs.iter().filter(|&&x| x <= 0.3 + 1e-12).count() - 1;
        assert!(k >= 2);
        for c in &cells[..k - 1] {
            assert!((c - cells[0]).abs() < 1e-12, "{cells:?}");
        }
        assert!(
            cells[k + 1] > 1.05 * cells[0] && cells[9] > 3.0 * cells[0],
            "{cells:?}"
        );
        // z from the top (grading below 1): the same, mirrored.
        let zs = coords("xmin", 2);
        let cz: Vec<f64> = zs.windows(2).map(|w| w[1] - w[0]).rev().collect();
        for (a, b) in cz.iter().zip(&cells) {
            assert!((a - b).abs() < 1e-12, "{cz:?} {cells:?}");
        }
    }

    #[test]
    fn hemisphere_quarter_of_every_hexahedron() {
        let radius = 2.0f64;
        let exact = std::f64::consts::PI / 6.0 * radius.powi(3);
        for kind in [ElementType::Hex8, ElementType::Hex20, ElementType::Hex27] {
            // (n_circ, n_rad, pole grading, radial grading, volume tolerance for Hex8, Hex20,
            // Hex27): the volume converges at O(h^2) for Hex8 (flat faces under the sphere) and
            // at O(h^4) for the quadratic elements, whose mid-nodes are on the sphere.
            let levels = [
                (3, 2, 1.0, 1.0, [0.035, 3e-4, 3e-5]),
                (4, 5, 20.0, 8.0, [0.05, 8e-4, 6e-4]),
                (8, 8, 20.0, 8.0, [0.012, 5e-5, 4e-5]),
                (6, 8, 40.0, 15.0, [0.03, 5e-4, 5e-4]),
            ];
            for (nc, nr, pole, rad, tols) in levels {
                let m = hemisphere_quarter(kind, nc, nr, radius, pole, 0.0, rad, "ball");
                let what = format!("{kind:?} n_circ {nc} n_rad {nr} grading {pole} {rad}");
                m.check().unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(m.num_elements(), nc * nc * nc + 3 * nc * nc * nr);
                let rel = (volume(&m) - exact).abs() / exact;
                let tol = match kind {
                    ElementType::Hex8 => tols[0],
                    ElementType::Hex20 => tols[1],
                    _ => tols[2],
                };
                assert!(rel < tol, "{what}: volume error {rel}");
                let centre = [0.0, 0.0, radius];
                let dist = |n: usize| {
                    let x = m.coords[n];
                    ((x[0] - centre[0]).powi(2)
                        + (x[1] - centre[1]).powi(2)
                        + (x[2] - centre[2]).powi(2))
                    .sqrt()
                };
                // Every node inside the quarter hemisphere, the pole a node.
                for (n, x) in m.coords.iter().enumerate() {
                    assert!(
                        x[0] >= 0.0 && x[1] >= 0.0 && x[2] >= 0.0 && x[2] <= radius,
                        "{what}"
                    );
                    assert!(dist(n) <= radius * (1.0 + 1e-14), "{what}");
                }
                assert!(m.coords.iter().any(|x| x.iter().all(|&c| c.abs() < 1e-15)));
                let fpc = 1;
                // The spherical surface: 3 nc^2 faces, every node on it at distance R, and every
                // node at distance R in it.
                assert_eq!(m.face_set("sphere").unwrap().len(), 3 * nc * nc * fpc);
                for n in m.nodes_of_set("sphere").unwrap() {
                    assert!((dist(n) - radius).abs() < 1e-13, "{what}");
                }
                let on_sphere = (0..m.num_nodes())
                    .filter(|&n| (dist(n) - radius).abs() < 1e-9)
                    .count();
                assert_eq!(m.node_set("sphere").unwrap().len(), on_sphere, "{what}");
                // The planes: flat z = R, symx x = 0, symy y = 0, each a face of the core and
                // the sides of two patches.
                let planes = [("flat", 2, radius), ("symx", 0, 0.0), ("symy", 1, 0.0)];
                for (name, d, value) in planes {
                    let faces = m.face_set(name).unwrap();
                    assert_eq!(faces.len(), nc * nc + 2 * nc * nr, "{what} {name}");
                    for n in m.nodes_of_set(name).unwrap() {
                        assert_eq!(m.coords[n][d], value, "{what} {name}");
                    }
                    let all = (0..m.num_nodes())
                        .filter(|&n| m.coords[n][d] == value)
                        .count();
                    assert_eq!(m.node_set(name).unwrap().len(), all, "{what} {name}");
                }
                // No internal seams: the boundary is exactly the four named face sets.
                let (xadj, _) = crate::mesh::partition::dual_graph(&m);
                let boundary = m.num_elements() * 6 - xadj[m.num_elements()];
                let named: usize = ["sphere", "flat", "symx", "symy"]
                    .iter()
                    .map(|s| m.face_sets[*s].len())
                    .sum();
                assert_eq!(boundary, named, "{what}");
            }
        }
    }

    /// With a pole zone, the surface nodes on a meridian are evenly spaced in polar angle
    /// over the zone, and the spacing grows beyond it.
    #[test]
    fn hemisphere_pole_zone_is_evenly_spaced() {
        let radius = 1.0;
        for kind in [ElementType::Hex8, ElementType::Hex27] {
            let m = hemisphere_quarter(kind, 8, 4, radius, 20.0, 0.3, 8.0, "ball");
            m.check().unwrap();
            // Polar angles of the sphere's nodes in the plane y = 0.
            let mut theta: Vec<f64> = m
                .nodes_of_set("sphere")
                .unwrap()
                .into_iter()
                .filter(|&n| m.coords[n][1] == 0.0)
                .map(|n| m.coords[n][0].atan2(radius - m.coords[n][2]))
                .collect();
            theta.sort_by(f64::total_cmp);
            let steps: Vec<f64> = theta.windows(2).map(|w| w[1] - w[0]).collect();
            // The nodes of the cells wholly inside the zone (a cell may straddle its end).
            let cell = kind.order() as f64 * steps[0];
            let in_zone = theta.iter().filter(|&&t| t <= 0.3 - cell + 1e-9).count() - 1;
            assert!(in_zone >= 6 * kind.order(), "{kind:?}: {theta:?}");
            for s in &steps[..in_zone] {
                assert!((s - steps[0]).abs() < 1e-9, "{kind:?}: {steps:?}");
            }
            assert!(
                steps[steps.len() - 1] > 10.0 * steps[0],
                "{kind:?}: {steps:?}"
            );
            assert!((theta[theta.len() - 1] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        }
    }

    #[test]
    fn merging_touching_boxes_shares_the_interface() {
        for kind in ALL {
            let mut a = box_mesh(kind, [2, 2, 2], [0.0; 3], [1.0; 3], "a");
            let b = box_mesh(kind, [2, 2, 2], [1.0, 0.0, 0.0], [2.0, 1.0, 1.0], "b");
            let (na, nb) = (a.num_nodes(), b.num_nodes());
            let iface = b.node_set("xmin").unwrap().len();
            a.merge(b);
            assert_eq!(a.num_nodes(), na + nb);
            assert_eq!(a.bodies, vec!["a".to_string(), "b".to_string()]);
            // Sets of the same name are united: "xmin" holds x = 0 and the interface x = 1.
            let fpc = if kind.is_hex() { 1 } else { 2 };
            assert_eq!(a.face_set("xmin").unwrap().len(), 2 * 4 * fpc);
            a.merge_coincident_nodes(1e-6);
            a.check().unwrap();
            assert_eq!(a.num_nodes(), na + nb - iface, "{kind:?}");
            assert!((volume(&a) - 2.0).abs() < 1e-12);
            let (xadj, _) = crate::mesh::partition::dual_graph(&a);
            let nf = a.types[0].num_faces();
            let boundary = a.num_elements() * nf - xadj[a.num_elements()];
            assert_eq!(boundary, 2 * (4 + 8 + 8) * fpc, "{kind:?}");
            // Node sets are renumbered: the interface x = 1 is in both "xmin" (of b) and "xmax".
            for &n in a.node_set("xmax").unwrap() {
                let x = a.coords[n][0];
                assert!(x == 1.0 || x == 2.0);
            }
        }
    }

    #[test]
    fn check_reports_inverted_elements_and_bad_indices() {
        let mut m = box_mesh(ElementType::Hex8, [2, 1, 1], [0.0; 3], [1.0; 3], "top");
        let (a, b) = (m.offsets[1], m.offsets[1] + 4);
        // Swap bottom and top faces of element 1: inverted.
        for k in 0..4 {
            m.conn.swap(a + k, b + k);
        }
        let e = m.check().unwrap_err().to_string();
        assert!(
            e.contains("element 1 (hex8, body 'top') is inverted"),
            "{e}"
        );
        assert!(e.contains("at its node 0"), "{e}");
        let mut m = box_mesh(ElementType::Tet10, [1, 1, 1], [0.0; 3], [1.0; 3], "b");
        m.conn[3] = 999;
        assert!(m
            .check()
            .unwrap_err()
            .to_string()
            .contains("element 0 (tet10"));
        let mut m = box_mesh(ElementType::Tet4, [1, 1, 1], [0.0; 3], [1.0; 3], "b");
        m.node_sets.get_mut("xmin").unwrap().push(100);
        assert!(m
            .check()
            .unwrap_err()
            .to_string()
            .contains("node set 'xmin'"));
        let mut m = box_mesh(ElementType::Tet4, [1, 1, 1], [0.0; 3], [1.0; 3], "b");
        m.face_sets.get_mut("zmax").unwrap().push(FaceRef {
            element: 0,
            face: 4,
        });
        assert!(m
            .check()
            .unwrap_err()
            .to_string()
            .contains("face set 'zmax'"));
    }

    #[test]
    fn curved_block_mid_nodes_are_mapped() {
        // A quarter annulus: mid-edge nodes of the arcs lie on the circles.
        let map = |u: [f64; 3]| {
            let r = 1.0 + u[0];
            let t = std::f64::consts::FRAC_PI_2 * u[1];
            [r * t.cos(), r * t.sin(), u[2]]
        };
        for kind in ALL {
            let m = mapped_block(kind, [2, 4, 1], map, "ring");
            m.check().unwrap();
            for &n in m.node_set("xmin").unwrap() {
                let x = m.coords[n];
                assert!(((x[0] * x[0] + x[1] * x[1]).sqrt() - 1.0).abs() < 1e-14);
            }
            let exact = std::f64::consts::PI / 4.0 * 3.0;
            let tol = if kind.order() == 1 { 0.03 } else { 1e-3 };
            assert!((volume(&m) - exact).abs() / exact < tol, "{kind:?}");
        }
    }
}
