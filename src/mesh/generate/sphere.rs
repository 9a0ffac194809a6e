//! Cube-sphere parts: a thick sphere octant and a quarter hemisphere, each a few mapped blocks
//! merged at their common nodes.
//!
//! # Sphere octant
//!
//! [`thick_sphere_octant`] is a cube-sphere: three blocks, one per face `x = 1`, `y = 1`, `z = 1`
//! of the cube `[0, 1]^3`. On patch `x = 1` the surface parameters `(s, t)` give the cube point
//! `(1, tan(pi s / 4), tan(pi t / 4))` (equal-angle spacing), projected radially to
//! `r(w) = r_in + w (r_out - r_in)`; the other patches are its cyclic permutations, so all three
//! maps are orientation preserving. Coincident nodes of the patches are merged.
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

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};
use std::rc::Rc;

use super::block::mapped_block;
use super::grading::{cell_ratio_exponent, exp_grading, ZoneGrading};
use crate::fe::ElementType;
use crate::mesh::Mesh;

/// A boxed parameter-to-space map.
type PatchMap = Box<dyn Fn([f64; 3]) -> [f64; 3]>;

/// One mapped block of a composite part.
struct Block {
    map: PatchMap,
    /// The part's names of the block's parameter sides `xmin`, `ymin`, `zmin`, `zmax` (`""`
    /// for a side inside the part).
    sides: [&'static str; 4],
    div: [usize; 3],
}

/// The blocks meshed, their sides renamed, merged in order, and their coincident nodes merged.
fn merge_blocks(kind: ElementType, blocks: impl IntoIterator<Item = Block>, body: &str) -> Mesh {
    let mut out = Mesh::new();
    for block in blocks {
        let mut part = mapped_block(kind, block.div, block.map, body);
        let rename: Vec<(&str, &str)> = ["xmin", "ymin", "zmin", "zmax"]
            .into_iter()
            .zip(block.sides)
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

/// `tan(pi s / 4)`, exactly 1 at `s = 1` and 0 at `s = 0`.
fn tan_quarter(s: f64) -> f64 {
    if s >= 1.0 {
        1.0
    } else {
        (FRAC_PI_4 * s).tan()
    }
}

/// The cube-sphere direction of patch `axis` (the cube face where coordinate `axis` is 1) at
/// the surface parameters `(s, t)`: on patch x `(1, tan(pi s / 4), tan(pi t / 4))`, on the
/// others its cyclic permutations.
fn patch_direction(axis: usize, s: f64, t: f64) -> [f64; 3] {
    match axis {
        0 => [1.0, tan_quarter(s), tan_quarter(t)],
        1 => [tan_quarter(t), 1.0, tan_quarter(s)],
        _ => [tan_quarter(s), tan_quarter(t), 1.0],
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
    // The names of the parameter sides xmin and ymin of the patches x = 1, y = 1, z = 1.
    let sides = [["symy", "symz"], ["symz", "symx"], ["symx", "symy"]];
    let blocks = (0..3).map(|axis| Block {
        map: Box::new(move |u: [f64; 3]| radial(u[2], patch_direction(axis, u[0], u[1]))),
        sides: [sides[axis][0], sides[axis][1], "inner", "outer"],
        div: [n_circ, n_circ, n_rad],
    });
    merge_blocks(kind, blocks, body)
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
    let frame = Rc::new(Hemisphere {
        radius,
        core: HEMISPHERE_CORE * radius,
        polar: PolarGrading::new(n_circ, radius, pole_grading, pole_zone),
        layers: shell_layers(n_rad, radial_grading),
    });
    // Final names: the plane x' = 0 becomes y = 0 ("symy") and y' = 0 becomes x = 0 ("symx");
    // z' = 0 is the flat face.
    let core = Block {
        map: Box::new({
            let frame = frame.clone();
            move |u: [f64; 3]| frame.core_point(u)
        }),
        sides: ["symy", "symx", "flat", ""],
        div: [n_circ, n_circ, n_circ],
    };
    let patch_sides = [
        ["symx", "flat", "", "sphere"],
        ["flat", "symy", "", "sphere"],
        ["symy", "symx", "", "sphere"],
    ];
    let patches = (0..3).map(|axis| {
        let frame = frame.clone();
        Block {
            map: Box::new(move |u: [f64; 3]| {
                frame.shell_point(u[2], patch_direction(axis, u[0], u[1]))
            }),
            sides: patch_sides[axis],
            div: [n_circ, n_circ, n_rad],
        }
    });
    merge_blocks(kind, std::iter::once(core).chain(patches), body)
}

/// The maps of [`hemisphere_quarter`]. Everything is built in the frame `(x', y', z')` with the
/// pole along `+z'` from the centre at the origin, then turned by
/// `(x', y', z') -> (y', x', R - z')` (two reflections: a proper rotation plus a shift).
struct Hemisphere {
    radius: f64,
    /// Half-size of the core cube.
    core: f64,
    polar: PolarGrading,
    /// The shell's layer boundaries, from the core (0) to the sphere (1).
    layers: Vec<f64>,
}

impl Hemisphere {
    /// A point of the building frame graded toward the pole and placed in the part's frame.
    fn place(&self, p: [f64; 3]) -> [f64; 3] {
        let q = polar_grading(p, self.radius, &self.polar);
        [q[1], q[0], self.radius - q[2]]
    }

    /// The core cube at parameter `u`.
    fn core_point(&self, u: [f64; 3]) -> [f64; 3] {
        let c = self.core;
        self.place([
            c * tan_quarter(u[0]),
            c * tan_quarter(u[1]),
            c * tan_quarter(u[2]),
        ])
    }

    /// The shell at depth parameter `w` along the ray of direction `d` (largest component 1).
    fn shell_point(&self, w: f64, d: [f64; 3]) -> [f64; 3] {
        // core * d is on a face of the core cube, and the sphere point on the same ray is
        // R d / |d|.
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        // Thin layers at the surface: the layers' boundaries at 1 - grading(1 - k / n_rad),
        // linear within a layer (mid-nodes halfway through their layer).
        let n_rad = self.layers.len() - 1;
        let t = (w * n_rad as f64).clamp(0.0, n_rad as f64);
        let k = (t.floor() as usize).min(n_rad - 1);
        let s = self.layers[k] + (t - k as f64) * (self.layers[k + 1] - self.layers[k]);
        let p: [f64; 3] = std::array::from_fn(|i| {
            let inner = self.core * d[i];
            let outer = self.radius * d[i] / n;
            inner + s * (outer - inner)
        });
        self.place(p)
    }
}

/// The `n_rad + 1` layer boundaries of the shell, `1 - exp_grading(1 - k / n_rad)`: the
/// outermost layer `1 / radial_grading` as thick as the innermost.
fn shell_layers(n_rad: usize, radial_grading: f64) -> Vec<f64> {
    let beta = cell_ratio_exponent(radial_grading, n_rad);
    (0..=n_rad)
        .map(|k| 1.0 - exp_grading(1.0 - k as f64 / n_rad as f64, beta))
        .collect()
}

/// The polar grading of [`hemisphere_quarter`]: `G` at the equal-angle knots
/// `theta_k = k pi / (2 cells)`, `k = 0..=cells`.
struct PolarGrading {
    identity: bool,
    knots: Vec<f64>,
}

impl PolarGrading {
    /// `G` of `n_circ` cells per patch side: the [`ZoneGrading`] of `[0, pi/2]` by `ratio` with
    /// the arc `zone` (on the sphere of `radius`) uniform, at the polar angles of the cells'
    /// corners along a meridian (`2 n_circ` equal-angle cells before grading).
    fn new(n_circ: usize, radius: f64, ratio: f64, zone: f64) -> PolarGrading {
        let smooth = ZoneGrading::new(ratio, zone / (FRAC_PI_2 * radius));
        let cells = 2 * n_circ;
        PolarGrading {
            identity: smooth.is_identity(),
            knots: (0..=cells)
                .map(|k| FRAC_PI_2 * smooth.map(k as f64 / cells as f64))
                .collect(),
        }
    }

    /// `G(theta)`, linear between the knots.
    fn at(&self, theta: f64) -> f64 {
        let cells = self.knots.len() - 1;
        let t = (theta / FRAC_PI_2 * cells as f64).clamp(0.0, cells as f64);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::test_support::{assert_boundary_is, expected_nodes, volume};

    const ALL: [ElementType; 5] = ElementType::ALL;

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
            // The boundary is exactly the five named face sets.
            let sets = ["inner", "outer", "symx", "symy", "symz"];
            assert_boundary_is(&m, &sets, &format!("{kind:?}"));
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
                // The boundary is exactly the four named face sets.
                assert_boundary_is(&m, &["sphere", "flat", "symx", "symy"], &what);
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
}
