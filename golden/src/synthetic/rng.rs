//! A counter-based random number generator: every stream is a pure function of
//! `(seed, stream, index)`, so results do not depend on thread count or generation order.

/// The splitmix64 increment (the golden ratio in 64-bit fixed point).
const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// The splitmix64 finaliser: a bijective 64-bit mix.
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A splitmix64 generator whose start state is hashed from `(seed, stream, index)`.
#[derive(Clone, Debug)]
pub struct HashRng {
    state: u64,
    /// The second normal of the last polar-method pair, not yet returned.
    spare: Option<f64>,
}

impl HashRng {
    /// The generator for item `index` of stream `stream` under `seed`.
    pub fn new(seed: u64, stream: u64, index: u64) -> Self {
        let s = mix64(mix64(seed.wrapping_add(GAMMA)) ^ stream.wrapping_mul(GAMMA));
        HashRng { state: mix64(s ^ index.wrapping_mul(0xD1B5_4A32_D192_ED03)), spare: None }
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GAMMA);
        mix64(self.state)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Uniform integer in `0..n` (`n > 0`), by the multiply-shift method.
    pub fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }

    /// A standard normal sample (Marsaglia's polar method; values come in pairs, the second
    /// is kept for the next call).
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        loop {
            let u = 2.0 * self.uniform() - 1.0;
            let v = 2.0 * self.uniform() - 1.0;
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let f = (-2.0 * s.ln() / s).sqrt();
                self.spare = Some(v * f);
                return u * f;
            }
        }
    }

    /// A uniformly distributed unit quaternion, w first (Shoemake's method).
    pub fn unit_quaternion(&mut self) -> [f64; 4] {
        let (u1, u2, u3) = (self.uniform(), self.uniform(), self.uniform());
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        let (t2, t3) = (std::f64::consts::TAU * u2, std::f64::consts::TAU * u3);
        [b * t3.cos(), a * t2.sin(), a * t2.cos(), b * t3.sin()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_pure_functions_of_their_key() {
        let a: Vec<u64> = (0..4).map(|_| HashRng::new(1, 2, 3).next_u64()).collect();
        assert!(a.iter().all(|&v| v == a[0]));
        assert_ne!(HashRng::new(1, 2, 3).next_u64(), HashRng::new(1, 2, 4).next_u64());
        assert_ne!(HashRng::new(1, 2, 3).next_u64(), HashRng::new(2, 2, 3).next_u64());
        assert_ne!(HashRng::new(1, 2, 3).next_u64(), HashRng::new(1, 3, 3).next_u64());
    }

    #[test]
    fn moments_are_right() {
        let mut r = HashRng::new(7, 0, 0);
        let n = 200_000;
        let (mut su, mut sn, mut sn2) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            su += r.uniform();
            let g = r.normal();
            sn += g;
            sn2 += g * g;
        }
        let n = n as f64;
        assert!((su / n - 0.5).abs() < 0.005);
        assert!((sn / n).abs() < 0.01);
        assert!((sn2 / n - 1.0).abs() < 0.02);
        let q = r.unit_quaternion();
        assert!((q.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((0..1000).all(|_| r.below(7) < 7));
    }
}
