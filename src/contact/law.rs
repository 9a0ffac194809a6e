//! Pointwise enforcement laws of frictional contact at one traction node A: penalty plus Uzawa
//! augmented Lagrangian, normal and Coulomb (docs/theory.md sections 1, 4 and 6; the paper's
//! eqs. 5 and 8). Physics only: the gap, slip and normal come from the caller (`contact::mortar`
//! and the nodal normals); here they are numbers.
//!
//! # Sign convention
//!
//! `nu` is the nodal normal of the secondary side, pointing from the secondary body toward the
//! primary body; `gh = nu . g_A / a_A` is the normalized gap, **positive in penetration**. The
//! nodal traction is `t_A = p nu + t_T` with `p >= 0` and `t_T . nu = 0`; the secondary node B
//! receives `-sum_A n1_AB t_A` and the primary node C receives `+sum_A n2_AC t_A`. So `t_A` is the
//! traction the secondary body exerts on the primary one: `+p nu` pushes the primary away, and
//! the secondary receives `-p nu`, pushed back out of the primary.
//!
//! `dsh` is the normalized mortar slip increment of docs/theory.md section 6,
//! `dsh = P [sum_C dn2_AC x2_C(t_n) - sum_B dn1_AB x1_B(t_n)] / a_A`. For one secondary face
//! at rest and a primary face translated by `v` (tangent, away from the edges), the primary
//! point under a secondary point is the material point that was at `x - v`, so
//! `sum_C n2_AC(t_n+1) x2_C(t_n) = sum_C n2_AC(t_n) x2_C(t_n) - a_A v` and `dsh = -v`: **`dsh` is
//! the slip of the secondary body relative to the primary body.** Friction must oppose it on the
//! secondary body, whose tangential force is `-t_T` (times positive weights): hence `t_T` must
//! point *along* `dsh` and the dissipation is `t_T . dsh >= 0`. The trial below, `+ eps_t dsh`,
//! does exactly that (tested with random states in slip from zero history).
//!
//! # Normal law
//!
//! `p = max(0, lambda_n + eps_n gh)`, `dp/dgh = eps_n` when `lambda_n + eps_n gh > 0`, else
//! `p = 0` and `dp/dgh = 0` (the kink itself counts as open). `lambda_n = 0` without updates is
//! plain penalty.
//!
//! # Coulomb law (return map)
//!
//! With `n = nu / |nu|` (the law normalizes `nu`, so it may be passed unnormalized),
//! `P = I - n (x) n`, the carried traction `q = traction_t_old + lambda_t` (in the old tangent
//! plane) and `R = R(nu_old, n)` the transport of [`transport`]:
//!
//! - trial: `t_tr = P (R q + eps_t dsh)` (any normal component of `dsh` is discarded);
//! - stick if `|t_tr| <= (1 - CONE_TIE) mu p`: `t_T = t_tr`;
//! - slip otherwise: `t_T = min(|t_tr|, mu p) m`, `m = t_tr / |t_tr|`; then `|t_T| = mu p`
//!   outside the cone, `t_T` is parallel to `t_tr` and orthogonal to `n`.
//!
//! The band [`CONE_TIE`] (1e-10 relative) settles a tie: a node that slipped in the last step
//! starts the next one carrying a traction on the cone, so its first trial (the predictor's,
//! `dsh = 0`) lies on the cone to round-off, and round-off alone (which differs between rank counts
//! and machines) would pick its first tangent, stick or slip; with the band it takes slip, whatever
//! the rank count (`tests/one_and_two_ranks_agree.rs`, `contact_one_and_two_ranks_agree`; the figures are in
//! docs/performance.md). Inside the band the traction is the trial, as in stick, so the traction is
//! that of the plain return map, continuous: the band chooses only the tangent (that of a slide
//! that goes on), as the touching band does (`touching_friction`).
//!
//! Derivatives returned in [`FrictionResult`] (matrices row-major: `d[i][j] = d t_T_i / d x_j`):
//!
//! - `dt_tr/d(dsh) = eps_t P`;
//! - `dt_tr/dn = P J_R - (n . y) I - n (x) y`, with `y = R q + eps_t dsh` and `J_R = d(R q)/dn`
//!   (below), then `dt_tr/dnu = dt_tr/dn (I - n (x) n) / |nu|` (the normalization is included,
//!   so the derivative is with respect to the three raw components of `nu`; the caller's
//!   `d nu` is tangent anyway);
//! - stick: `dt_T/dx = dt_tr/dx`, `dt_T/dp = 0`;
//! - slip: `dt_T/dx = (mu p / |t_tr|) (I - m (x) m) dt_tr/dx`, `dt_T/dp = mu m`.
//!
//! The slip factor `mu p / |t_tr|` is below `1 / (1 - CONE_TIE)` in slip, so the tangent stays
//! bounded however small `t_tr` is. The only division by `|t_tr|` happens in slip, where
//! `|t_tr| > (1 - CONE_TIE) mu p >= 0`; the norm
//! is computed with scaling (no underflow to 0 for components around 1e-200, no overflow around
//! 1e200), so `t_tr -> 0` gives no NaN: `t_tr = 0` exactly is stick
//! (`0 <= (1 - CONE_TIE) mu p`), and a tiny
//! nonzero `t_tr` above a tinier cone is normalized safely.
//!
//! Shortcuts (nothing else computed, all outputs zero): `p <= 0` gives [`Status::Open`],
//! `mu = 0` with `p > 0` gives [`Status::Slip`] (frictionless sliding). A NaN `p` is not hidden:
//! it propagates into the traction.
//!
//! # Transport of the old traction
//!
//! The old tangential traction and multiplier live in the tangent plane of `nu_old` (the normal
//! when they were stored). They are carried into the current plane by the **minimal rotation**
//! taking `a = nu_old/|nu_old|` to `b = nu/|nu|`: the rotation about `a x b` by the angle between
//! them (Rodrigues), written without angles or normalized axes as
//!
//! `R v = c v + w x v + (w . v) / (1 + c) w`,   `c = a . b`, `w = a x b`.
//!
//! It keeps lengths, maps `a` to `b` and the old tangent plane onto the new one, and is the
//! identity when `b = a` (`w = 0`, `c = 1`, exactly). For a normal turning along a great circle
//! (a rigid rotation about an axis in the tangent plane) increments compose exactly; otherwise
//! two increments differ from the direct one by a rotation about the normal of the order of the
//! solid angle swept (second order in the increment). With `v` fixed and `a` fixed,
//! `J_R = d(R v)/db = v (x) a - [v]x [a]x + s [a]x + w (x) ((v x a) / (1 + c) - s a / (1 + c))`,
//! `s = (w . v) / (1 + c)`, `[u]x` the cross-product matrix.
//!
//! `1 + c` is evaluated as `|a + b|^2 / 2`, without cancellation, so the rotation keeps lengths
//! to about `1e-16 / sqrt(1 + c)` relative even for normals close to opposite.
//!
//! Degenerate cases: a zero `v` is returned as is (nothing to carry). A zero `nu_old` means "no
//! old plane yet" (the [`NodeHistory::default`] state): the transport is the identity, and the
//! projection `P` of the trial puts whatever is carried into the current plane. `nu = -nu_old`
//! (`1 + c < `[`TRANSPORT_ANTIPODAL_TOL`]) has no unique minimal rotation and is **refused**:
//! [`try_transport`] returns `None` and [`transport`] panics. [`friction_traction`] and
//! [`uzawa_update`] do not panic there: they drop the carried traction (as if
//! `traction_t_old + lambda_t = 0`) and [`FrictionResult::history_dropped`] says so, for the
//! caller to count or cut the step.
//!
//! # History and Uzawa
//!
//! [`NodeHistory`] holds, fixed inside a Newton solve: `lambda_n`; `traction_t_old`, the converged
//! `t_T` of the previous load step, and `normal_old`, the normal it was stored with; `lambda_t`,
//! the tangential multiplier *increment of the current step*, in the old tangent plane (so the
//! total carried traction is `q = traction_t_old + lambda_t`).
//!
//! [`uzawa_update`], after a converged solve: `lambda_n <- p = max(0, lambda_n + eps_n gh)`, and
//! `lambda_t <- R^T t_T - traction_t_old` with `t_T` the return-mapped traction at that state
//! (`R^T = R(n, nu_old)`, the transport back into the old plane), so that the next solve's trial
//! is `t_T + eps_t dsh`: for a sticking node this is `lambda_t += eps_t dsh`, the classical update
//! whose fixed point is zero slip error. With `gh = 0`, `dsh = 0` and a consistent history
//! (`lambda_n >= 0`, `q` in the old plane, `|q| <= mu lambda_n`) the update is a fixed point.
//!
//! [`commit_step`], after the last solve of a load step: `traction_t_old <- t_T`,
//! `normal_old <- n`, `lambda_t <- 0`, `lambda_n` kept (the next step starts from it; setting it to
//! `p` would count the current penetration twice).

use nalgebra::{Matrix3, Vector3};

/// Below this value of `1 + nu_old . nu` (unit normals) the transport is refused: the normals
/// are opposite to within about 1.4e-4 rad and the rotation axis is undefined.
pub const TRANSPORT_ANTIPODAL_TOL: f64 = 1e-8;

/// Penalty factors and friction coefficient of one node.
#[derive(Clone, Copy, Debug)]
pub struct LawParams {
    /// Normal penalty `eps_n` (pressure per unit normalized gap).
    pub eps_n: f64,
    /// Tangential penalty `eps_t` (traction per unit normalized slip).
    pub eps_t: f64,
    /// Coulomb coefficient `mu >= 0`.
    pub mu: f64,
}

/// The Uzawa multipliers and history of one node (held fixed inside a Newton solve).
#[derive(Clone, Copy, Debug, Default)]
pub struct NodeHistory {
    /// Normal multiplier `lambda_n >= 0`.
    pub lambda_n: f64,
    /// Tangential multiplier increment of the current load step, in the old tangent plane.
    pub lambda_t: [f64; 3],
    /// The normal `traction_t_old` was stored with; zero means "not set yet" (no transport).
    pub normal_old: [f64; 3],
    /// The converged tangential traction of the previous load step (tangent to `normal_old`).
    pub traction_t_old: [f64; 3],
}

/// Status of a node under the Coulomb law.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// `p = 0`, or a node inside the touching band ([`touching_friction`]): no tangential
    /// traction.
    Open,
    /// `|t_tr| <= (1 - CONE_TIE) mu p`: `t_T = t_tr`.
    Stick,
    /// `|t_tr| > (1 - CONE_TIE) mu p` (or `mu = 0` with `p > 0`):
    /// `t_T = min(|t_tr|, mu p) t_tr / |t_tr|`.
    Slip,
}

/// Frictional traction at a node and its derivatives (matrices row-major:
/// `m[i][j] = d t_T_i / d x_j`).
#[derive(Clone, Copy, Debug)]
pub struct FrictionResult {
    /// `t_T`, tangent to `nu`.
    pub traction: [f64; 3],
    /// Open, stick or slip.
    pub status: Status,
    /// The trial `t_tr` (zero when the shortcut `p <= 0` or `mu = 0` was taken).
    pub trial: [f64; 3],
    /// `d t_T / d dsh`.
    pub d_dsh: [[f64; 3]; 3],
    /// `d t_T / d p`.
    pub d_p: [f64; 3],
    /// `d t_T / d nu` (raw components of `nu`, normalization included).
    pub d_nu: [[f64; 3]; 3],
    /// The old traction could not be transported (`nu` opposite to `normal_old`) and was dropped.
    pub history_dropped: bool,
}

impl FrictionResult {
    /// The frictionless result at pressure `p`: no tangential traction, [`Status::Slip`] when
    /// pressed (as the law reports `mu = 0`), [`Status::Open`] otherwise.
    pub(crate) fn frictionless(p: f64) -> FrictionResult {
        FrictionResult::zero(if p > 0.0 { Status::Slip } else { Status::Open })
    }

    /// No traction, no derivatives, with `status`.
    fn zero(status: Status) -> FrictionResult {
        FrictionResult {
            traction: [0.0; 3],
            status,
            trial: [0.0; 3],
            d_dsh: [[0.0; 3]; 3],
            d_p: [0.0; 3],
            d_nu: [[0.0; 3]; 3],
            history_dropped: false,
        }
    }
}

/// Normal law: `p = max(0, lambda_n + eps_n gh)` and `dp/dgh` (`eps_n` when closed, 0 when open;
/// `lambda_n + eps_n gh = 0` counts as open).
pub fn normal_pressure(lambda_n: f64, eps_n: f64, gh: f64) -> (f64, f64) {
    let x = lambda_n + eps_n * gh;
    if x > 0.0 {
        (x, eps_n)
    } else {
        (0.0, 0.0)
    }
}

/// The normal law of a node in the bilateral iteration (`contact::frictional`): `p = lambda_n +
/// eps_n gh` whatever its sign, and `dp/dgh = eps_n`. An opening pulls the node back with a
/// tension, so that one Newton step of the bilateral problem closes what a linearization left
/// open.
pub fn bilateral_pressure(lambda_n: f64, eps_n: f64, gh: f64) -> (f64, f64) {
    (lambda_n + eps_n * gh, eps_n)
}

/// [`normal_pressure`] with a touching band: a node whose `lambda_n + eps_n gh` lies in
/// `(-eps_n touch, 0]` (a gap within `touch` of closing, e.g. surfaces that touch to round-off)
/// gets `p = 0` but the closed derivative `dp/dgh = eps_n`. Both values of the derivative are
/// valid generalized derivatives at the kink; the closed one keeps a body that rests on another
/// (touching, no load yet) from floating freely in the first Newton iteration. `touch = 0` is
/// [`normal_pressure`].
pub fn normal_pressure_touching(lambda_n: f64, eps_n: f64, gh: f64, touch: f64) -> (f64, f64) {
    let x = lambda_n + eps_n * gh;
    if x > -eps_n * touch {
        (x.max(0.0), eps_n)
    } else {
        (0.0, 0.0)
    }
}

/// True when a pressure `p` from [`normal_pressure_touching`] carries friction: `p` above what
/// a penetration of the touching band gives (`eps_n touch`). Below it, a pressed or touching
/// node takes [`touching_friction`].
///
/// Surfaces that start in contact touch to round-off: their weighted gaps are `+-1e-16`, and
/// a round-off penetration gives a round-off pressure. The Coulomb law on that pressure would
/// take a stick or a slip state per node, and a slip direction, from the last bits of the gaps
/// (so from the summation order or the quadrature rule); inside the band no friction is taken
/// from them.
pub fn carries_friction(p: f64, eps_n: f64, touch: f64) -> bool {
    p > eps_n * touch
}

/// The friction of a node inside the touching band (see [`carries_friction`]): no tangential
/// traction, and the tangent of sticking, `d t_T / d dsh = eps_t (I - nu nu)`.
///
/// This is the tangential twin of the band's closed normal derivative
/// ([`normal_pressure_touching`]): touching surfaces hold each other in the first Newton
/// iteration, tangentially as well as normally, whatever the round-off of their gaps. Where
/// surfaces first touch (no slip, no carried traction) the stick derivative is a limit of the
/// law's derivatives in its stick region, so a valid generalized derivative. Elsewhere in the
/// band (a node unloading through it, with slip or history) it is not the derivative of the
/// residual, whose tangential traction is zero: Newton may lose a quadratic step there, on a
/// band `1e-10 h` thick. The Coulomb traction left out is at most `mu eps_n touch`
/// (`1e-8 mu E` with the default penalty); with the stick predictor (`mu = infinity`) the
/// band carries no stick traction either. The status is [`Status::Open`]: the node carries no
/// tangential traction and has no slip to enforce in the Uzawa loop.
///
/// # Panics
/// If `nu` is zero.
pub fn touching_friction(nu: [f64; 3], prm: &LawParams) -> FrictionResult {
    let (n, _) = unit(nu);
    let d_dsh = (Matrix3::identity() - n * n.transpose()) * prm.eps_t;
    FrictionResult {
        d_dsh: to_rows(&d_dsh),
        ..FrictionResult::zero(Status::Open)
    }
}

/// The tangential law of a node with pressure `p` (and `dp_dgh`, from
/// [`normal_pressure_touching`] with the band `touch`), normal `nu` and slip `dsh`: inside the
/// touching band the band's stick tangent ([`touching_friction`]), else where pressed the Coulomb
/// return map ([`friction_traction`]; with `stick_all`, the stick predictor's `mu = infinity`),
/// else no friction; frictionless (`mu = 0`) a pure pressure.
pub fn tangential_law(
    history: &NodeHistory,
    prm: &LawParams,
    nu: [f64; 3],
    (p, dp_dgh): (f64, f64),
    dsh: [f64; 3],
    (touch, stick_all): (f64, bool),
) -> FrictionResult {
    let touching = dp_dgh > 0.0 && !carries_friction(p, prm.eps_n, touch);
    if prm.mu > 0.0 && touching {
        touching_friction(nu, prm)
    } else if prm.mu > 0.0 && p > 0.0 {
        let law = if stick_all {
            LawParams {
                mu: f64::INFINITY,
                ..*prm
            }
        } else {
            *prm
        };
        friction_traction(history, &law, nu, p, dsh)
    } else {
        FrictionResult::frictionless(p)
    }
}

/// Euclidean norm with scaling: no underflow for tiny components, no overflow for huge ones.
fn norm3(v: &Vector3<f64>) -> f64 {
    let s = v.amax();
    if s == 0.0 || !s.is_finite() {
        return s;
    }
    let u = v / s;
    s * u.dot(&u).sqrt()
}

fn to_arr(v: &Vector3<f64>) -> [f64; 3] {
    [v[0], v[1], v[2]]
}

fn to_rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
    ]
}

/// `nu / |nu|` and `|nu|`.
///
/// # Panics
/// If `nu` is zero (a caller bug: nodal normals never vanish).
fn unit(nu: [f64; 3]) -> (Vector3<f64>, f64) {
    let v = Vector3::from(nu);
    let len = norm3(&v);
    assert!(len != 0.0, "contact law: zero normal");
    (v / len, len)
}

/// `1 + a . b` for unit `a`, `b`, as `|a + b|^2 / 2`: no cancellation when `b` is near `-a`
/// (`1 + a . b` computed directly loses `1e-16 / (1 + c)` in relative terms).
fn one_plus_cos(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    0.5 * (a + b).norm_squared()
}

/// The minimal rotation taking unit `a` to unit `b`, applied to `v`, or `None` if antipodal.
fn rotate(v: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> Option<Vector3<f64>> {
    let c = a.dot(b);
    let opc = one_plus_cos(a, b);
    if opc < TRANSPORT_ANTIPODAL_TOL {
        return None;
    }
    let w = a.cross(b);
    if w == Vector3::zeros() && c > 0.0 {
        // Same normal: the identity, exactly (c may be 1 - ulp).
        return Some(*v);
    }
    Some(c * v + w.cross(v) + (w.dot(v) / opc) * w)
}

/// `R(a, b) v` and its derivative with respect to `b` (for fixed `a`, `v`); `None` if antipodal.
fn rotate_with_jacobian(
    v: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let c = a.dot(b);
    let opc = one_plus_cos(a, b);
    if opc < TRANSPORT_ANTIPODAL_TOL {
        return None;
    }
    let w = a.cross(b);
    let s = w.dot(v) / opc;
    let rv = if w == Vector3::zeros() && c > 0.0 {
        *v
    } else {
        c * v + w.cross(v) + s * w
    };
    let ax = a.cross_matrix();
    let vx = v.cross_matrix();
    let ds = v.cross(a) / opc - (s / opc) * a;
    let jac = v * a.transpose() - vx * ax + s * ax + w * ds.transpose();
    Some((rv, jac))
}

/// Rotates a tangential vector `v` from the old tangent plane (normal `nu_old`) into the new one
/// (normal `nu`) by the minimal rotation (about `nu_old x nu`) taking `nu_old` to `nu`; lengths
/// are kept. Normals need not be unit. `None` when `nu` is opposite to `nu_old`
/// (`1 + cos < `[`TRANSPORT_ANTIPODAL_TOL`]) and `v != 0`. A zero `v` is returned unchanged; a
/// zero `nu_old` (history not set) gives the identity. See the module docs.
///
/// # Panics
/// If `nu` is zero while `v` and `nu_old` are not.
pub fn try_transport(v: [f64; 3], nu_old: [f64; 3], nu: [f64; 3]) -> Option<[f64; 3]> {
    if v == [0.0; 3] || nu_old == [0.0; 3] {
        return Some(v);
    }
    let (a, _) = unit(nu_old);
    let (b, _) = unit(nu);
    rotate(&Vector3::from(v), &a, &b).map(|r| to_arr(&r))
}

/// Rotates a tangential vector from the old tangent plane (normal `nu_old`) into the new one
/// (`nu`): the rotation about `nu_old x nu` taking `nu_old` to `nu`, applied to `v`, keeping its
/// length: `R v = c v + w x v + (w . v)/(1 + c) w`, `c = a . b`, `w = a x b` with the unit
/// normals `a`, `b`. `nu == nu_old` is the identity exactly; a zero `v` or a zero `nu_old` (no
/// old plane yet) returns `v`.
///
/// # Panics
/// If `nu == -nu_old` (within [`TRANSPORT_ANTIPODAL_TOL`]) and `v != 0`: there is no unique
/// rotation; use [`try_transport`] to handle it. Also if `nu` is zero.
pub fn transport(v: [f64; 3], nu_old: [f64; 3], nu: [f64; 3]) -> [f64; 3] {
    try_transport(v, nu_old, nu).expect(
        "contact law: transport refused, the normal reversed (nu == -nu_old): no unique rotation",
    )
}

/// Relative band below the Coulomb cone that counts as on it, in slip (module docs, "Coulomb
/// law"): `|t_tr| > (1 - CONE_TIE) mu p` is slip.
pub const CONE_TIE: f64 = 1e-10;

/// Frictional traction at a node: `t_T` from the trial
/// `t_tr = P (R(nu_old, nu) (traction_t_old + lambda_t) + eps_t dsh)`, stick if
/// `|t_tr| <= (1 - CONE_TIE) mu p`, else slip `t_T = min(|t_tr|, mu p) t_tr / |t_tr|`; with the
/// derivatives with respect to `dsh`, `p` and `nu` (module docs). `p <= 0` returns zeros and
/// [`Status::Open`], `mu = 0` returns zeros and [`Status::Slip`], without computing anything
/// else.
///
/// # Panics
/// If `nu` is zero.
pub fn friction_traction(
    h: &NodeHistory,
    prm: &LawParams,
    nu: [f64; 3],
    p: f64,
    dsh: [f64; 3],
) -> FrictionResult {
    if p <= 0.0 {
        return FrictionResult::zero(Status::Open);
    }
    if prm.mu == 0.0 {
        return FrictionResult::zero(Status::Slip);
    }
    let (n, len) = unit(nu);
    let proj = Matrix3::identity() - n * n.transpose();
    let q = Vector3::from(h.traction_t_old) + Vector3::from(h.lambda_t);

    // Carried traction R q and its derivative with respect to the unit normal.
    let mut history_dropped = false;
    let (rq, jr) = if q == Vector3::zeros() || h.normal_old == [0.0; 3] {
        (q, Matrix3::zeros())
    } else {
        let (a, _) = unit(h.normal_old);
        match rotate_with_jacobian(&q, &a, &n) {
            Some(x) => x,
            None => {
                history_dropped = true;
                (Vector3::zeros(), Matrix3::zeros())
            }
        }
    };

    let y = rq + prm.eps_t * Vector3::from(dsh);
    let trial = proj * y;
    let dtr_ddsh = prm.eps_t * proj;
    let dtr_dn = proj * jr - n.dot(&y) * Matrix3::identity() - n * y.transpose();
    let dtr_dnu = dtr_dn * (proj / len);

    let cone = prm.mu * p;
    let tn = norm3(&trial);
    let (traction, status, d_dsh, d_p, d_nu) = if tn <= cone * (1.0 - CONE_TIE) {
        (trial, Status::Stick, dtr_ddsh, Vector3::zeros(), dtr_dnu)
    } else {
        // Slip: tn > (1 - CONE_TIE) cone >= 0, so the division is safe and cone / tn is at
        // most 1 / (1 - CONE_TIE). Inside the band (tn <= cone) the traction stays the trial:
        // only the tangent is slip's.
        let m = trial / tn;
        let dm = (cone / tn) * (Matrix3::identity() - m * m.transpose());
        (
            // Not `cone.min(tn)`, which would hide a NaN cone.
            if tn < cone { tn } else { cone } * m,
            Status::Slip,
            dm * dtr_ddsh,
            prm.mu * m,
            dm * dtr_dnu,
        )
    };
    FrictionResult {
        traction: to_arr(&traction),
        status,
        trial: to_arr(&trial),
        d_dsh: to_rows(&d_dsh),
        d_p: to_arr(&d_p),
        d_nu: to_rows(&d_nu),
        history_dropped,
    }
}

/// The pressure `p = max(0, lambda_n + eps_n gh)` and the return-mapped traction with it at
/// this state (what the Uzawa update and the end of a step store).
fn traction_at(
    h: &NodeHistory,
    prm: &LawParams,
    nu: [f64; 3],
    gh: f64,
    dsh: [f64; 3],
) -> (f64, FrictionResult) {
    let (p, _) = normal_pressure(h.lambda_n, prm.eps_n, gh);
    (p, friction_traction(h, prm, nu, p, dsh))
}

/// Uzawa updates after a converged solve: `lambda_n <- max(0, lambda_n + eps_n gh)`;
/// `lambda_t <- R(nu, nu_old) t_T - traction_t_old`, with `t_T` the return-mapped traction at
/// this state (computed with the updated pressure), brought back into the old tangent plane, so
/// that the carried traction of the next solve is `t_T`. `normal_old` and `traction_t_old` are
/// kept. If the transport is refused (`nu == -nu_old`) the carried traction is dropped:
/// `lambda_t = -traction_t_old`.
///
/// # Panics
/// If `nu` is zero.
pub fn uzawa_update(
    h: &NodeHistory,
    prm: &LawParams,
    nu: [f64; 3],
    gh: f64,
    dsh: [f64; 3],
) -> NodeHistory {
    let (p, fr) = traction_at(h, prm, nu, gh, dsh);
    let old = Vector3::from(h.traction_t_old);
    let back = if h.normal_old == [0.0; 3] {
        Some(Vector3::from(fr.traction))
    } else {
        let (a, _) = unit(h.normal_old);
        let (b, _) = unit(nu);
        rotate(&Vector3::from(fr.traction), &b, &a)
    };
    let lambda_t = match back {
        Some(t) if !fr.history_dropped => t - old,
        _ => -old,
    };
    NodeHistory {
        lambda_n: p,
        lambda_t: to_arr(&lambda_t),
        normal_old: h.normal_old,
        traction_t_old: h.traction_t_old,
    }
}

/// Closes a load step (after its last solve): `traction_t_old <- t_T` at this state,
/// `normal_old <- nu / |nu|`, `lambda_t <- 0`, `lambda_n` kept.
///
/// # Panics
/// If `nu` is zero.
pub fn commit_step(
    h: &NodeHistory,
    prm: &LawParams,
    nu: [f64; 3],
    gh: f64,
    dsh: [f64; 3],
) -> NodeHistory {
    let (_, fr) = traction_at(h, prm, nu, gh, dsh);
    let (n, _) = unit(nu);
    NodeHistory {
        lambda_n: h.lambda_n,
        lambda_t: [0.0; 3],
        normal_old: to_arr(&n),
        traction_t_old: fr.traction,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v3(a: [f64; 3]) -> Vector3<f64> {
        Vector3::from(a)
    }

    #[test]
    fn a_bilateral_node_is_pulled_back_where_the_law_opens_it() {
        let (lambda, eps) = (50.0, 1e6);
        // Open by twice the multiplier's reach: the law releases the node, the bilateral law
        // pulls it back.
        let gh = -2.0 * lambda / eps;
        assert_eq!(normal_pressure_touching(lambda, eps, gh, 1e-10), (0.0, 0.0));
        assert_eq!(bilateral_pressure(lambda, eps, gh), (-lambda, eps));
        // Pressed: the two agree.
        let gh = 1e-6;
        assert_eq!(
            bilateral_pressure(lambda, eps, gh),
            normal_pressure(lambda, eps, gh)
        );
    }

    #[test]
    fn friction_starts_above_the_touching_band() {
        let (eps, touch) = (1e5, 1e-10);
        // A round-off penetration inside the band: touching, no friction.
        let (p, dp) = normal_pressure_touching(0.0, eps, 0.5 * touch, touch);
        assert!(p > 0.0 && dp == eps);
        assert!(!carries_friction(p, eps, touch));
        // Just beyond the band, or held by a multiplier: friction.
        let (p, _) = normal_pressure_touching(0.0, eps, 2.0 * touch, touch);
        assert!(carries_friction(p, eps, touch));
        let (p, _) = normal_pressure_touching(1.0, eps, 0.0, touch);
        assert!(carries_friction(p, eps, touch));
        // Open: none.
        assert!(!carries_friction(0.0, eps, touch));
    }

    #[test]
    fn touching_friction_is_the_stick_tangent_without_traction() {
        let prm = LawParams {
            eps_n: 1e5,
            eps_t: 300.0,
            mu: 0.3,
        };
        let nu = [0.0, 0.6, 0.8];
        let t = touching_friction([0.0, 1.2, 1.6], &prm);
        assert_eq!(t.traction, [0.0; 3]);
        assert_eq!(t.status, Status::Open);
        assert_eq!((t.d_p, t.d_nu), ([0.0; 3], [[0.0; 3]; 3]));
        // The law's own stick derivative at a small slip: the same matrix.
        let h = NodeHistory::default();
        let stick = friction_traction(&h, &prm, nu, 1.0, [1e-9, 0.0, 0.0]);
        assert_eq!(stick.status, Status::Stick);
        for i in 0..3 {
            for j in 0..3 {
                assert!((t.d_dsh[i][j] - stick.d_dsh[i][j]).abs() < 1e-12, "{i} {j}");
            }
        }
    }

    fn nrm(a: [f64; 3]) -> f64 {
        norm3(&v3(a))
    }

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        v3(a).dot(&v3(b))
    }

    fn unitv(a: [f64; 3]) -> [f64; 3] {
        to_arr(&v3(a).normalize())
    }

    fn tangent(v: [f64; 3], n: [f64; 3]) -> [f64; 3] {
        let n = v3(n).normalize();
        to_arr(&(v3(v) - n * n.dot(&v3(v))))
    }

    fn all_finite(r: &FrictionResult) -> bool {
        r.traction
            .iter()
            .chain(r.trial.iter())
            .chain(r.d_p.iter())
            .chain(r.d_dsh.iter().flatten())
            .chain(r.d_nu.iter().flatten())
            .all(|x| x.is_finite())
    }

    /// Central differences of `f` at `x0` (step `h`), compared with `jac` (row-major): the largest
    /// entry error must be below `tol` times the largest entry of `jac` (at least 1e-3 of it is
    /// asserted to be nonzero so the comparison means something). Returns the relative error.
    fn check_jac(
        f: impl Fn([f64; 3]) -> [f64; 3],
        x0: [f64; 3],
        jac: [[f64; 3]; 3],
        h: f64,
        tol: f64,
        what: &str,
    ) -> f64 {
        let scale = jac.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 1e-3, "{what}: jacobian trivially zero");
        let mut err = 0.0f64;
        for j in 0..3 {
            let mut xp = x0;
            let mut xm = x0;
            xp[j] += h;
            xm[j] -= h;
            let (fp, fm) = (f(xp), f(xm));
            for i in 0..3 {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                err = err.max((fd - jac[i][j]).abs());
            }
        }
        let rel = err / scale;
        assert!(rel < tol, "{what}: FD relative error {rel:e} >= {tol:e}");
        rel
    }

    // ---------------------------------------------------------------- normal law

    #[test]
    fn normal_open_closed_and_derivative() {
        let eps = 250.0;
        assert_eq!(normal_pressure(0.0, eps, -1e-3), (0.0, 0.0));
        assert_eq!(normal_pressure(0.0, eps, 0.0), (0.0, 0.0)); // the kink counts as open
        let (p, dp) = normal_pressure(0.0, eps, 2e-3);
        assert!((p - 0.5).abs() < 1e-15 && dp == eps);
        // Derivative by central differences (tolerance 1e-9 relative), closed and open.
        for &gh in &[2e-3, -2e-3] {
            let hh = 1e-7;
            let fd = (normal_pressure(0.0, eps, gh + hh).0 - normal_pressure(0.0, eps, gh - hh).0)
                / (2.0 * hh);
            let (_, dp) = normal_pressure(0.0, eps, gh);
            assert!((fd - dp).abs() <= 1e-9 * eps, "gh {gh}: fd {fd} vs {dp}");
        }
    }

    #[test]
    fn normal_lambda_shift() {
        // p(lambda, eps, gh) = p(0, eps, gh + lambda / eps): the multiplier shifts the gap.
        let eps = 1e3;
        for &lam in &[0.0, 0.7, 3.0] {
            for &gh in &[-5e-3, -1e-3, 0.0, 1e-3, 4e-3] {
                let a = normal_pressure(lam, eps, gh);
                let b = normal_pressure(0.0, eps, gh + lam / eps);
                assert!((a.0 - b.0).abs() < 1e-12 && a.1 == b.1, "{lam} {gh}");
            }
        }
        // With lambda > 0, contact holds with a small separation: gh = -lambda / (2 eps).
        let (p, dp) = normal_pressure(2.0, eps, -1e-3);
        assert!((p - 1.0).abs() < 1e-12 && dp == eps);
    }

    // ---------------------------------------------------------------- friction: derivatives

    /// A node whose normal turned by about 0.3 rad since its traction was stored, with a
    /// nonzero multiplier increment: every term of the derivative is exercised.
    fn state() -> (NodeHistory, LawParams, [f64; 3]) {
        let n_old = unitv([0.1, -0.2, 1.0]);
        let nu = unitv([0.35, 0.1, 0.95]);
        let h = NodeHistory {
            lambda_n: 0.0,
            lambda_t: tangent([0.05, 0.2, 0.0], n_old),
            normal_old: n_old,
            traction_t_old: tangent([0.6, -0.3, 0.1], n_old),
        };
        let prm = LawParams {
            eps_n: 1e3,
            eps_t: 50.0,
            mu: 0.4,
        };
        (h, prm, nu)
    }

    fn check_all_derivatives(
        h: &NodeHistory,
        prm: &LawParams,
        nu: [f64; 3],
        p: f64,
        dsh: [f64; 3],
    ) {
        let r = friction_traction(h, prm, nu, p, dsh);
        let tr = |x| friction_traction(h, prm, nu, p, x).traction;
        // Tolerance 1e-7 relative with steps 1e-6 (truncation ~1e-12, round-off ~1e-10).
        check_jac(tr, dsh, r.d_dsh, 1e-6, 1e-7, "d/d dsh");
        let tn = |x| friction_traction(h, prm, x, p, dsh).traction;
        check_jac(tn, nu, r.d_nu, 1e-6, 1e-7, "d/d nu");
        let hp = 1e-6 * p;
        let fp = friction_traction(h, prm, nu, p + hp, dsh).traction;
        let fm = friction_traction(h, prm, nu, p - hp, dsh).traction;
        for i in 0..3 {
            let fd = (fp[i] - fm[i]) / (2.0 * hp);
            assert!(
                (fd - r.d_p[i]).abs() <= 1e-7 * prm.mu.max(1.0),
                "d/dp {i}: {fd} vs {}",
                r.d_p[i]
            );
        }
        // Derivatives at an unnormalized normal too (the normalization is differentiated).
        let nu2 = [2.5 * nu[0], 2.5 * nu[1], 2.5 * nu[2]];
        let r2 = friction_traction(h, prm, nu2, p, dsh);
        let tn2 = |x| friction_traction(h, prm, x, p, dsh).traction;
        check_jac(tn2, nu2, r2.d_nu, 1e-6, 1e-7, "d/d nu (|nu| = 2.5)");
    }

    #[test]
    fn derivatives_in_stick() {
        let (h, prm, nu) = state();
        let dsh = tangent([2e-3, 1e-3, 0.0], nu);
        let p = 20.0;
        let r = friction_traction(&h, &prm, nu, p, dsh);
        assert_eq!(r.status, Status::Stick);
        assert!(nrm(r.trial) < 0.5 * prm.mu * p);
        assert_eq!(r.d_p, [0.0; 3]);
        check_all_derivatives(&h, &prm, nu, p, dsh);
    }

    #[test]
    fn derivatives_in_slip() {
        let (h, prm, nu) = state();
        let dsh = tangent([0.05, -0.03, 0.01], nu);
        let p = 2.0;
        let r = friction_traction(&h, &prm, nu, p, dsh);
        assert_eq!(r.status, Status::Slip);
        assert!(nrm(r.trial) > 2.0 * prm.mu * p);
        check_all_derivatives(&h, &prm, nu, p, dsh);
        slip_properties(&r, &prm, nu, p);
    }

    fn slip_properties(r: &FrictionResult, prm: &LawParams, nu: [f64; 3], p: f64) {
        let t = r.traction;
        let n = unitv(nu);
        // |t_T| = mu p (1e-14 relative), parallel to and along t_tr, orthogonal to nu.
        assert!(
            (nrm(t) - prm.mu * p).abs() <= 1e-14 * prm.mu * p,
            "|t| {} vs {}",
            nrm(t),
            prm.mu * p
        );
        let cross = v3(t).cross(&v3(r.trial)).norm();
        assert!(
            cross <= 1e-14 * nrm(t) * nrm(r.trial),
            "not parallel: {cross:e}"
        );
        assert!(dot(t, r.trial) > 0.0);
        assert!(
            dot(t, n).abs() <= 1e-14 * nrm(t),
            "not tangent: {:e}",
            dot(t, n)
        );
    }

    #[test]
    fn derivatives_near_the_cone() {
        let (h, prm, nu) = state();
        let dsh = tangent([0.01, 0.004, 0.0], nu);
        let tn = nrm(friction_traction(&h, &prm, nu, 1.0, dsh).trial);
        // Just inside (stick) and just outside (slip): 1e-3 from the cone, FD steps 1e-6.
        for (f, st) in [(1.001, Status::Stick), (0.999, Status::Slip)] {
            let p = f * tn / prm.mu;
            let r = friction_traction(&h, &prm, nu, p, dsh);
            assert_eq!(r.status, st);
            check_all_derivatives(&h, &prm, nu, p, dsh);
            if st == Status::Slip {
                slip_properties(&r, &prm, nu, p);
            }
        }
    }

    /// A trial on the cone to round-off (a node that slipped, at the start of its next step) is
    /// slip on either side of the cone, so round-off does not pick its first tangent; a trial
    /// 1e-9 inside is stick, as without the band.
    #[test]
    fn trial_on_the_cone_to_round_off_is_slip() {
        let (h, prm, nu) = state();
        let dsh = tangent([0.01, 0.004, 0.0], nu);
        let tn = nrm(friction_traction(&h, &prm, nu, 1.0, dsh).trial);
        for (f, st) in [
            (1.0 + 1e-13, Status::Slip),
            (1.0, Status::Slip),
            (1.0 - 1e-13, Status::Slip),
            (1.0 + 1e-9, Status::Stick),
            // Either side of the band's lower edge.
            ((1.0 + 1e-14) / (1.0 - CONE_TIE), Status::Stick),
            ((1.0 - 1e-14) / (1.0 - CONE_TIE), Status::Slip),
        ] {
            let p = f * tn / prm.mu;
            let r = friction_traction(&h, &prm, nu, p, dsh);
            assert_eq!(r.status, st, "cone / |t_tr| = {f}");
            // The traction of the plain return map, continuous: the trial inside the cone, its
            // projection on the cone outside, to round-off.
            let cone = prm.mu * p;
            let expected = v3(r.trial) * (cone.min(tn) / tn);
            assert!((v3(r.traction) - expected).norm() <= 1e-14 * tn, "at {f}");
        }
    }

    #[test]
    fn normal_component_of_dsh_is_discarded() {
        let (h, prm, nu) = state();
        let dsh = tangent([0.01, 0.004, 0.0], nu);
        let n = unitv(nu);
        let dsh2 = [
            dsh[0] + 0.3 * n[0],
            dsh[1] + 0.3 * n[1],
            dsh[2] + 0.3 * n[2],
        ];
        let a = friction_traction(&h, &prm, nu, 1.0, dsh);
        let b = friction_traction(&h, &prm, nu, 1.0, dsh2);
        for i in 0..3 {
            assert!((a.traction[i] - b.traction[i]).abs() < 1e-14);
        }
    }

    // ---------------------------------------------------------------- dissipation

    proptest! {
        // No regression files in the tree.
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        /// From zero history, in slip: t_T . dsh = mu p |dsh| >= 0 for a slip increment tangent
        /// to nu (as the caller's P [...] / a_A is). dsh is the slip of the secondary body
        /// relative to the primary one and the secondary receives -t_T, so friction opposes the
        /// relative slip (module docs). Tolerance 1e-13 relative on the equality; the sign is
        /// asserted strictly (> 0). A flipped sign in the trial makes both fail.
        #[test]
        fn slip_dissipates(
            nx in -1.0f64..1.0, ny in -1.0f64..1.0, nz in -1.0f64..1.0,
            sx in -1.0f64..1.0, sy in -1.0f64..1.0, sz in -1.0f64..1.0,
            mag in -6.0f64..0.0, mu in 0.01f64..1.5, eps_t in 1e-2f64..1e4, frac in 0.01f64..0.99,
        ) {
            let nu = [nx, ny, nz];
            prop_assume!(nrm(nu) > 0.1);
            let s = 10f64.powf(mag);
            let dsh = tangent([s * sx, s * sy, s * sz], nu);
            let pd = nrm(dsh);
            prop_assume!(pd > 1e-3 * s);
            let prm = LawParams { eps_n: 1.0, eps_t, mu };
            let p = frac * eps_t * pd / mu;
            let r = friction_traction(&NodeHistory::default(), &prm, nu, p, dsh);
            prop_assert_eq!(r.status, Status::Slip);
            let d = dot(r.traction, dsh);
            prop_assert!(d > 0.0, "dissipation {d:e} <= 0");
            prop_assert!((d - mu * p * pd).abs() <= 1e-13 * mu * p * pd);
        }
    }

    // ---------------------------------------------------------------- transport

    fn rot_x(th: f64) -> Matrix3<f64> {
        let (s, c) = th.sin_cos();
        Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
    }

    proptest! {
        // No regression files in the tree.
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        /// Keeps length, maps nu_old to nu and the old tangent plane into the new one, and
        /// back-transport is the inverse: all to `tol = 4e-15 / sqrt(1 + c)` relative (at most
        /// 1.3e-13 here, with 1 + c > 1e-3).
        #[test]
        fn transport_is_a_rotation_between_planes(
            a in prop::array::uniform3(-1.0f64..1.0),
            b in prop::array::uniform3(-1.0f64..1.0),
            v in prop::array::uniform3(-1.0f64..1.0),
        ) {
            prop_assume!(nrm(a) > 0.1 && nrm(b) > 0.1 && nrm(v) > 1e-3);
            let (ua, ub) = (unitv(a), unitv(b));
            prop_assume!(1.0 + dot(ua, ub) > 1e-3);
            let tol = 4e-15 / (1.0 + dot(ua, ub)).sqrt();
            let r = transport(v, a, b);
            prop_assert!((nrm(r) - nrm(v)).abs() <= tol * nrm(v));
            let ra = transport(ua, a, b);
            prop_assert!((v3(ra) - v3(ub)).norm() <= tol);
            let vt = tangent(v, a);
            let rt = transport(vt, a, b);
            prop_assert!(dot(rt, ub).abs() <= tol * nrm(v));
            let back = transport(r, b, a);
            prop_assert!((v3(back) - v3(v)).norm() <= tol * nrm(v));
        }
    }

    #[test]
    fn transport_identity_and_degenerate_cases() {
        let n = unitv([0.3, -0.4, 0.8]);
        let v = tangent([1.0, 2.0, 3.0], n);
        assert_eq!(transport(v, n, n), v); // exactly
        assert_eq!(transport(v, [0.0; 3], n), v); // no old plane yet
        assert_eq!(transport([0.0; 3], n, [-n[0], -n[1], -n[2]]), [0.0; 3]);
        assert!(try_transport(v, n, [-n[0], -n[1], -n[2]]).is_none());
        // Unnormalized normals give the same rotation (1e-15).
        let r1 = transport(v, n, [0.0, 0.0, 1.0]);
        let r2 = transport(v, [3.0 * n[0], 3.0 * n[1], 3.0 * n[2]], [0.0, 0.0, 0.2]);
        assert!((v3(r1) - v3(r2)).norm() < 1e-15 * nrm(v));
    }

    #[test]
    #[should_panic(expected = "transport refused")]
    fn transport_refuses_a_reversed_normal() {
        transport([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]);
    }

    #[test]
    fn transport_composes() {
        let v = [0.7, -0.2, 0.0];
        let z = [0.0, 0.0, 1.0];
        // Along a great circle (axis x): increments compose exactly (1e-15).
        let a = z;
        let b = to_arr(&(rot_x(0.01) * v3(z)));
        let c = to_arr(&(rot_x(0.025) * v3(z)));
        let two = transport(transport(v, a, b), b, c);
        let one = transport(v, a, c);
        assert!((v3(two) - v3(one)).norm() < 1e-15);
        // Off a great circle: the mismatch is second order (the swept solid angle): halving the
        // increment divides it by about 4 (between 3.5 and 4.5), and it is below d^2 |v|.
        let err = |d: f64| {
            let a = z;
            let b = unitv([d, 0.0, 1.0]);
            let c = unitv([d, d, 1.0]);
            let v = [0.7, -0.2, 0.0];
            (v3(transport(transport(v, a, b), b, c)) - v3(transport(v, a, c))).norm()
        };
        let (e1, e2) = (err(1e-2), err(5e-3));
        assert!(e1 < 1e-4 * nrm(v) && e1 > 0.0, "{e1:e}");
        let ratio = e1 / e2;
        assert!((3.5..4.5).contains(&ratio), "ratio {ratio}");
    }

    /// Rigid rotation of a sticking node by `total` about `axis` in `steps` increments: each step
    /// solves with dsh = 0 (rigid motion gives no mortar slip) and commits. Returns the traction
    /// history and the final normal.
    fn rotate_sticking_node(axis: [f64; 3], total: f64, steps: usize) -> (Vec<[f64; 3]>, [f64; 3]) {
        let n0 = [0.0, 0.0, 1.0];
        let prm = LawParams {
            eps_n: 1e3,
            eps_t: 1e3,
            mu: 0.5,
        };
        let gh = 1e-2; // p = 10, cone 5
        let mut h = NodeHistory {
            lambda_n: 0.0,
            lambda_t: [0.0; 3],
            normal_old: n0,
            traction_t_old: [1.0, 2.0, 0.0],
        };
        let ax = v3(axis).normalize();
        let mut out = vec![h.traction_t_old];
        let mut nu = n0;
        for k in 1..=steps {
            let rot = nalgebra::Rotation3::from_axis_angle(
                &nalgebra::Unit::new_normalize(ax),
                total * k as f64 / steps as f64,
            );
            nu = to_arr(&(rot * v3(n0)));
            let (p, _) = normal_pressure(h.lambda_n, prm.eps_n, gh);
            let r = friction_traction(&h, &prm, nu, p, [0.0; 3]);
            assert_eq!(r.status, Status::Stick);
            assert!(dot(r.traction, nu).abs() < 1e-14);
            h = commit_step(&h, &prm, nu, gh, [0.0; 3]);
            assert_eq!(h.traction_t_old, r.traction);
            out.push(r.traction);
        }
        (out, nu)
    }

    #[test]
    fn sticking_node_rotated_rigidly_keeps_its_traction() {
        let half_pi = std::f64::consts::FRAC_PI_2;
        // About x (the normal's path is a great circle): |t| constant to 1e-12 and the traction is
        // the rigidly rotated one to 1e-12.
        let (ts, nu) = rotate_sticking_node([1.0, 0.0, 0.0], half_pi, 10);
        let m0 = nrm(ts[0]);
        for t in &ts {
            assert!((nrm(*t) - m0).abs() < 1e-12, "{} vs {m0}", nrm(*t));
        }
        assert!((v3(nu) - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-15);
        let exact = rot_x(half_pi) * Vector3::new(1.0, 2.0, 0.0);
        assert!((v3(*ts.last().unwrap()) - exact).norm() < 1e-12);
        // About a tilted axis (the normal sweeps a cone): |t| still constant to 1e-12 and tangent.
        let (ts, nu) = rotate_sticking_node([1.0, 0.5, 0.7], half_pi, 10);
        for t in &ts[1..] {
            assert!((nrm(*t) - m0).abs() < 1e-12);
        }
        assert!(dot(*ts.last().unwrap(), nu).abs() < 1e-14);
    }

    // ---------------------------------------------------------------- robustness

    #[test]
    fn mu_zero_and_p_zero_give_zero_traction() {
        let (h, mut prm, nu) = state();
        let dsh = [0.01, 0.02, 0.0];
        prm.mu = 0.0;
        let r = friction_traction(&h, &prm, nu, 5.0, dsh);
        assert_eq!(r.status, Status::Slip);
        assert_eq!(r.traction, [0.0; 3]);
        assert!(all_finite(&r));
        prm.mu = 0.4;
        let r = friction_traction(&h, &prm, nu, 0.0, dsh);
        assert_eq!(r.status, Status::Open);
        assert_eq!(r.traction, [0.0; 3]);
        assert!(all_finite(&r));
        // A NaN pressure is not hidden.
        let r = friction_traction(&h, &prm, nu, f64::NAN, dsh);
        assert!(r.traction.iter().any(|x| x.is_nan()));
    }

    #[test]
    fn zero_and_tiny_trial_give_no_nan() {
        let prm = LawParams {
            eps_n: 1.0,
            eps_t: 1.0,
            mu: 0.3,
        };
        let nu = [0.0, 0.0, 1.0];
        // t_tr = 0 exactly: stick, zero traction, finite tangent.
        let r = friction_traction(&NodeHistory::default(), &prm, nu, 1.0, [0.0; 3]);
        assert_eq!(r.status, Status::Stick);
        assert_eq!(r.traction, [0.0; 3]);
        assert!(all_finite(&r));
        // Tiny t_tr (1e-200: its squares underflow) outside a tinier cone: slip, |t| = mu p.
        let p = 1e-250;
        let r = friction_traction(&NodeHistory::default(), &prm, nu, p, [1e-200, -2e-200, 0.0]);
        assert_eq!(r.status, Status::Slip);
        assert!(all_finite(&r));
        assert!((nrm(r.traction) / (prm.mu * p) - 1.0).abs() < 1e-14);
        // Huge t_tr (squares overflow): still finite.
        let r = friction_traction(&NodeHistory::default(), &prm, nu, 1.0, [1e200, 1e200, 0.0]);
        assert!(all_finite(&r));
        assert!((nrm(r.traction) - prm.mu).abs() < 1e-14);
    }

    #[test]
    fn extreme_penalties_stay_finite() {
        let (h, _, nu) = state();
        for &eps in &[1e12, 1e-12] {
            let prm = LawParams {
                eps_n: eps,
                eps_t: eps,
                mu: 0.3,
            };
            for &gh in &[1e-3, -1e-3] {
                let (p, dp) = normal_pressure(0.0, eps, gh);
                assert!(p.is_finite() && dp.is_finite());
                for dsh in [[1e-3, 0.0, 0.0], [0.0; 3], [1e-15, 1e-15, 0.0]] {
                    let r = friction_traction(&h, &prm, nu, p, dsh);
                    assert!(all_finite(&r), "eps {eps} gh {gh} dsh {dsh:?}");
                    assert!(nrm(r.traction) <= prm.mu * p * (1.0 + 1e-14));
                    let hn = uzawa_update(&h, &prm, nu, gh, dsh);
                    assert!(hn.lambda_n.is_finite() && hn.lambda_t.iter().all(|x| x.is_finite()));
                }
            }
        }
    }

    #[test]
    fn reversed_normal_drops_the_history() {
        let (h, prm, _) = state();
        let n = h.normal_old;
        let nu = [-n[0], -n[1], -n[2]];
        let r = friction_traction(&h, &prm, nu, 10.0, [0.0; 3]);
        assert!(r.history_dropped && all_finite(&r));
        assert_eq!(r.traction, [0.0; 3]);
        let hn = uzawa_update(&h, &prm, nu, 1e-2, [0.0; 3]);
        assert!(hn.lambda_t.iter().all(|x| x.is_finite()));
    }

    // ---------------------------------------------------------------- Uzawa

    #[test]
    fn uzawa_fixed_point_when_the_constraint_is_met() {
        let (mut h, prm, nu) = state();
        h.lambda_n = 5.0; // cone mu lambda_n = 2 > |q| ~ 0.8: a consistent sticking state
                          // Also with no old plane yet: then the carried traction must be tangent to nu.
        let unset = NodeHistory {
            normal_old: [0.0; 3],
            lambda_t: tangent(h.lambda_t, nu),
            traction_t_old: tangent(h.traction_t_old, nu),
            ..h
        };
        for hist in [h, unset] {
            let hn = uzawa_update(&hist, &prm, nu, 0.0, [0.0; 3]);
            assert_eq!(hn.lambda_n, hist.lambda_n);
            assert_eq!(hn.normal_old, hist.normal_old);
            assert_eq!(hn.traction_t_old, hist.traction_t_old);
            // Rotated into the new plane and back: 1e-14.
            let d = (v3(hn.lambda_t) - v3(hist.lambda_t)).norm();
            assert!(d < 1e-14, "lambda_t moved by {d:e}");
        }
        // Not a fixed point when the constraint is violated (the test can fail).
        let hn = uzawa_update(&h, &prm, nu, 1e-3, [0.0; 3]);
        assert!((hn.lambda_n - (5.0 + prm.eps_n * 1e-3)).abs() < 1e-12);
        let dsh = tangent([1e-3, 0.0, 0.0], nu);
        let hn = uzawa_update(&h, &prm, nu, 0.0, dsh);
        // Sticking node: the carried traction grows by eps_t dsh (seen in the new plane).
        let q0 = v3(transport(
            to_arr(&(v3(h.traction_t_old) + v3(h.lambda_t))),
            h.normal_old,
            nu,
        ));
        let q1 = v3(transport(
            to_arr(&(v3(hn.traction_t_old) + v3(hn.lambda_t))),
            h.normal_old,
            nu,
        ));
        assert!((q1 - q0 - prm.eps_t * v3(dsh)).norm() < 1e-13);
    }

    #[test]
    fn uzawa_in_slip_carries_the_return_mapped_traction() {
        let (mut h, prm, nu) = state();
        h.lambda_n = 1.0;
        let dsh = tangent([0.05, -0.03, 0.0], nu);
        let (p, _) = normal_pressure(h.lambda_n, prm.eps_n, 1e-3);
        let r = friction_traction(&h, &prm, nu, p, dsh);
        assert_eq!(r.status, Status::Slip);
        let hn = uzawa_update(&h, &prm, nu, 1e-3, dsh);
        // The next solve at dsh = 0 sees exactly t_T (1e-14), on the cone.
        let r2 = friction_traction(&hn, &prm, nu, hn.lambda_n, [0.0; 3]);
        assert!((v3(r2.traction) - v3(r.traction)).norm() < 1e-14);
    }
}
