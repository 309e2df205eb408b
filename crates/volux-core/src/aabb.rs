//! World-space axis-aligned bounding boxes.

/// A world-space axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    /// Minimum corner.
    pub min: glam::DVec3,
    /// Maximum corner.
    pub max: glam::DVec3,
}

impl Aabb {
    /// The smallest box holding all `points`; `None` when empty.
    pub fn from_points(points: impl IntoIterator<Item = glam::DVec3>) -> Option<Self> {
        let mut it = points.into_iter();
        let first = it.next()?;
        let (min, max) = it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
        Some(Self { min, max })
    }
    /// Centre of the box.
    pub fn center(&self) -> glam::DVec3 {
        (self.min + self.max) * 0.5
    }
    /// The eight corners (bit 0 of the index picks max x, bit 1 max y, bit 2 max z).
    pub fn corners(&self) -> [glam::DVec3; 8] {
        std::array::from_fn(|i| {
            let pick = |bit: usize, lo: f64, hi: f64| if i & bit == 0 { lo } else { hi };
            glam::DVec3::new(
                pick(1, self.min.x, self.max.x),
                pick(2, self.min.y, self.max.y),
                pick(4, self.min.z, self.max.z),
            )
        })
    }
    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).length()
    }
}
