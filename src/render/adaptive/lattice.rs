//! One tile's lattice of points, `2^D` steps per pixel: what is traced, what is queued, which squares split,
//! and the pixel values that follow.

use crate::math::Rgb;

use super::Point;

/// One tile's lattice: each point's colour and id once traced, whether it is traced or queued, and for each
/// square's top-left point the number of levels at which the squares anchored there were split.
#[derive(Default)]
pub(super) struct Lattice {
    width: u32,
    points: Vec<Point>,
    claimed: Vec<bool>,
    split: Vec<u8>,
}

impl Lattice {
    /// An empty `width × height` lattice (buffers kept from the previous tile).
    pub(super) fn reset(&mut self, width: u32, height: u32) {
        let n = (width * height) as usize;
        self.width = width;
        self.points.resize(n, Point::default());
        self.claimed.clear();
        self.claimed.resize(n, false);
        self.split.clear();
        self.split.resize(n, 0);
    }
    fn index(&self, (x, y): (u32, u32)) -> usize {
        (y * self.width + x) as usize
    }
    pub(super) fn get(&self, p: (u32, u32)) -> &Point {
        &self.points[self.index(p)]
    }
    pub(super) fn set(&mut self, p: (u32, u32), point: Point) {
        let i = self.index(p);
        self.points[i] = point;
        self.claimed[i] = true;
    }
    /// Sets `p` when a neighbour traced it.
    pub(super) fn load(&mut self, p: (u32, u32), point: Option<Point>) {
        if let Some(point) = point {
            self.set(p, point);
        }
    }
    /// The point at `p` once traced.
    pub(super) fn known(&self, p: (u32, u32)) -> Option<Point> {
        let i = self.index(p);
        self.claimed[i].then(|| self.points[i])
    }
    /// Marks `p` to be traced; false when it is traced or marked already.
    pub(super) fn claim(&mut self, p: (u32, u32)) -> bool {
        let i = self.index(p);
        !std::mem::replace(&mut self.claimed[i], true)
    }
    /// Records that the square at `p` of `level` is split.
    pub(super) fn mark_split(&mut self, p: (u32, u32), level: u32) {
        let i = self.index(p);
        self.split[i] = level as u8 + 1;
    }
    /// The value of the square at `p` of `level` (size `unit >> level`): its quarters' mean when split,
    /// else its corners' mean.
    pub(super) fn value(&self, (x, y): (u32, u32), unit: u32, level: u32) -> Rgb {
        let s = unit >> level;
        let parts = if u32::from(self.split[self.index((x, y))]) > level {
            let h = s / 2;
            [(x, y), (x + h, y), (x, y + h), (x + h, y + h)].map(|q| self.value(q, unit, level + 1))
        } else {
            [(x, y), (x + s, y), (x, y + s), (x + s, y + s)].map(|p| self.get(p).colour)
        };
        (parts[0] + parts[1] + parts[2] + parts[3]) * 0.25
    }
}
