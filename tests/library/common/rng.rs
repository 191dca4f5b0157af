//! Seeded random numbers from the contract's generator ([`SplitMix64`]), so failures reproduce.

use bareray::math::SplitMix64;
use glam::DVec3;

pub struct Rng(SplitMix64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(SplitMix64::new(seed))
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0.unit()
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    /// 10^U(lo, hi).
    pub fn log(&mut self, lo: f64, hi: f64) -> f64 {
        10f64.powf(self.range(lo, hi))
    }
    /// A uniform unit vector (rejection from the cube, normalised).
    pub fn dir(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
    /// A random unit vector perpendicular to `n`.
    pub fn tangent(&mut self, n: DVec3) -> DVec3 {
        loop {
            let t = self.dir().reject_from(n);
            if t.length() > 0.1 {
                return t.normalize();
            }
        }
    }
}
