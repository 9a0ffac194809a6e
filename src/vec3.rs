//! Three-vectors as `[T; 3]`: the few operations the geometry kernels share.
//!
//! Generic over [`Scalar`] (`f64`, or a forward-mode dual number), so that the float kernels
//! and their dual-number twins use one definition. Every operation is written out component by
//! component, left to right: the float and the dual code round the same way.

use num_dual::DualNum;

/// The scalars of the generic face kernels (`*_at` functions): `f64`, or a forward-mode dual
/// number over `f64` such as `num_dual::DualSVec64<N>`, so that one code gives the values and
/// (with duals) their exact derivatives. The `f64` instances compile to the plain float code.
pub trait Scalar: DualNum<Primitive = f64> + Copy {}

impl<T: DualNum<Primitive = f64> + Copy> Scalar for T {}

/// A three-vector.
pub type Vec3<T = f64> = [T; 3];

/// `a . b`.
pub fn dot<T: Scalar>(a: Vec3<T>, b: Vec3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a x b`.
pub fn cross<T: Scalar>(a: Vec3<T>, b: Vec3<T>) -> Vec3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a - b`.
pub fn sub<T: Scalar>(a: Vec3<T>, b: Vec3<T>) -> Vec3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `|a|`.
pub fn norm<T: Scalar>(a: Vec3<T>) -> T {
    dot(a, a).sqrt()
}

/// `a / |a|`, if `|a|` (its real part) is positive and finite.
pub fn normalized<T: Scalar>(a: Vec3<T>) -> Option<Vec3<T>> {
    let n = norm(a);
    (n.re() > 0.0 && n.re().is_finite()).then(|| a.map(|v| v / n))
}

/// The part of `v` tangent to the unit normal `nu`: `v - (v . nu) nu`.
pub fn tangential(v: Vec3, nu: Vec3) -> Vec3 {
    let d = dot(v, nu);
    std::array::from_fn(|c| v[c] - d * nu[c])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_of_the_unit_vectors() {
        let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        assert_eq!(cross(x, y), z);
        assert_eq!(cross(y, z), x);
        assert_eq!(cross(z, x), y);
        assert_eq!(dot(x, y), 0.0);
        assert_eq!(norm([3.0, 4.0, 12.0]), 13.0);
        assert_eq!(sub([3.0, 4.0, 12.0], x), [2.0, 4.0, 12.0]);
        assert_eq!(normalized([0.0, 0.0, -2.0]), Some([0.0, 0.0, -1.0]));
        assert_eq!(normalized([0.0; 3]), None);
        assert_eq!(normalized([f64::INFINITY, 0.0, 0.0]), None);
        assert_eq!(tangential([1.0, 2.0, 3.0], z), [1.0, 2.0, 0.0]);
    }
}
