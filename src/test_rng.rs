//! A small deterministic random generator for the unit tests (xorshift64): the same points on
//! every platform and run.

/// xorshift64 state; any non-zero seed.
pub(crate) struct Rng(pub u64);

impl Rng {
    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[-amplitude, amplitude)`.
    pub fn symmetric(&mut self, amplitude: f64) -> f64 {
        amplitude * (2.0 * self.uniform() - 1.0)
    }

    /// Uniform in `[-1, 1)`.
    pub fn sym(&mut self) -> f64 {
        self.symmetric(1.0)
    }

    /// A point of the parent domain `[-1, 1]^D` (`cube`) or of the unit simplex.
    pub fn point<const D: usize>(&mut self, cube: bool) -> [f64; D] {
        loop {
            let p: [f64; D] = std::array::from_fn(|_| self.uniform());
            if cube {
                return p.map(|t| 2.0 * t - 1.0);
            }
            if p.iter().sum::<f64>() <= 1.0 {
                return p;
            }
        }
    }
}
