//! [`GridSpec`]: where a voxel grid sits in world space. Convention (the CPU↔GPU contract):
//! voxel `(i, j, k)` covers `origin + [i, i+1)·voxel_size` on each axis, its centre is at `+0.5`.

use glam::{DVec3, UVec3, Vec3};

use crate::morton::MAX_COORD;
use crate::{Error, Result};

/// A regular voxel grid: origin (min corner), cubic voxel edge length and dimensions.
///
/// The origin and size are kept in `f64`: the voxelizers map vertices into grid space on the host
/// in double precision before snapping them to a fixed-point lattice, which is what makes the
/// occupancy independent of the scene's scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSpec {
    /// World-space position of the grid's minimum corner.
    pub origin: DVec3,
    /// Edge length of one voxel in world units.
    pub voxel_size: f64,
    /// Number of voxels along each axis.
    pub dims: UVec3,
}

impl GridSpec {
    /// Largest extent per axis: 2²¹, what a 63-bit Morton code addresses.
    pub const MAX_DIM: u32 = MAX_COORD;

    /// A grid, validated: finite origin, positive finite size, every dimension in
    /// `1..=MAX_DIM`.
    pub fn new(origin: DVec3, voxel_size: f64, dims: UVec3) -> Result<Self> {
        let grid = Self { origin, voxel_size, dims };
        grid.validate()?;
        Ok(grid)
    }

    /// Checks the invariants [`GridSpec::new`] establishes (fields are public).
    pub fn validate(&self) -> Result<()> {
        if !self.origin.is_finite() {
            return Err(Error::InvalidGrid {
                reason: format!("origin {} is not finite", self.origin),
            });
        }
        if !(self.voxel_size.is_finite() && self.voxel_size > 0.0) {
            return Err(Error::InvalidGrid {
                reason: format!("voxel size {} is not a positive finite number", self.voxel_size),
            });
        }
        if self.dims.min_element() == 0 {
            return Err(Error::InvalidGrid {
                reason: format!("dimensions {} contain a zero", self.dims),
            });
        }
        if self.dims.max_element() > Self::MAX_DIM {
            return Err(Error::GridTooLarge {
                requested: self.dims.as_u64vec3().to_array(),
                max: Self::MAX_DIM as u64,
            });
        }
        Ok(())
    }

    /// The grid fitted to the bounds `[min, max]` with `resolution` voxels along the longest
    /// axis. The longest axis gets exactly `resolution` voxels; the others get enough voxels to
    /// cover the bounds (at least one). The origin is `min`, so geometry lying on the maximum
    /// bound touches the last voxel's far face and is voxelized into it.
    ///
    /// ```
    /// use glam::{DVec3, UVec3};
    /// use voxlod_format::GridSpec;
    /// let g = GridSpec::fit(DVec3::ZERO, DVec3::new(2.0, 1.0, 0.5), 64).unwrap();
    /// assert_eq!(g.dims, UVec3::new(64, 32, 16));
    /// assert_eq!(g.voxel_size, 2.0 / 64.0);
    /// ```
    pub fn fit(min: DVec3, max: DVec3, resolution: u32) -> Result<Self> {
        let bad =
            |reason| Error::InvalidBounds { min: min.to_array(), max: max.to_array(), reason };
        if !min.is_finite() || !max.is_finite() {
            return Err(bad("the bounds are not finite"));
        }
        if max.cmplt(min).any() {
            return Err(bad("the bounds are empty (max < min)"));
        }
        let extent = max - min;
        let longest = extent.max_element();
        if longest <= 0.0 {
            return Err(bad("the bounds are a single point"));
        }
        if resolution == 0 || resolution > Self::MAX_DIM {
            return Err(Error::GridTooLarge {
                requested: [resolution as u64; 3],
                max: Self::MAX_DIM as u64,
            });
        }
        let voxel_size = longest / resolution as f64;
        // Relative slack so that an axis as long as the longest one does not get an extra voxel
        // from rounding.
        let cells = extent / voxel_size * (1.0 - 1e-12);
        let dims = cells.ceil().max(DVec3::ONE).as_uvec3().min(UVec3::splat(resolution));
        Self::new(min, voxel_size, dims)
    }

    /// Total number of voxels (as `u64`: a 2²¹³ grid overflows `u32`).
    pub fn voxel_count(&self) -> u64 {
        self.dims.as_u64vec3().element_product()
    }

    /// World-space maximum corner.
    pub fn max_corner(&self) -> DVec3 {
        self.origin + self.dims.as_dvec3() * self.voxel_size
    }

    /// World-space minimum corner of voxel `c`.
    pub fn voxel_min(&self, c: UVec3) -> DVec3 {
        self.origin + c.as_dvec3() * self.voxel_size
    }

    /// World-space centre of voxel `c`.
    pub fn voxel_center(&self, c: UVec3) -> DVec3 {
        self.origin + (c.as_dvec3() + 0.5) * self.voxel_size
    }

    /// Continuous grid coordinates of a world position (voxel `i` spans `[i, i+1)`).
    pub fn to_grid(&self, p: DVec3) -> DVec3 {
        (p - self.origin) / self.voxel_size
    }

    /// The voxel containing world position `p`, if inside the grid.
    pub fn voxel_of(&self, p: DVec3) -> Option<UVec3> {
        let g = self.to_grid(p).floor();
        if g.cmpge(DVec3::ZERO).all() && g.cmplt(self.dims.as_dvec3()).all() {
            Some(g.as_uvec3())
        } else {
            None
        }
    }

    /// Whether `c` is a voxel of this grid.
    pub fn contains(&self, c: UVec3) -> bool {
        c.cmplt(self.dims).all()
    }

    /// Origin as `f32`, for renderers and GPU uniforms.
    pub fn origin_f32(&self) -> Vec3 {
        self.origin.as_vec3()
    }

    /// Voxel size as `f32`, for renderers and GPU uniforms.
    pub fn voxel_size_f32(&self) -> f32 {
        self.voxel_size as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_gives_longest_axis_exactly_the_resolution() {
        for res in [1, 7, 64, 128, 255, 256, 1000] {
            let g =
                GridSpec::fit(DVec3::new(-0.1, 0.2, 0.3), DVec3::new(0.9, 0.7, 1.3), res).unwrap();
            assert_eq!(g.dims.x, res);
            assert_eq!(g.dims.z, res, "x and z extents are equal");
            assert!(g.max_corner().cmpge(DVec3::new(0.9, 0.7, 1.3) - 1e-12).all());
        }
    }

    #[test]
    fn fit_rejects_bad_bounds() {
        assert!(GridSpec::fit(DVec3::ZERO, DVec3::ZERO, 8).is_err());
        assert!(GridSpec::fit(DVec3::ZERO, DVec3::new(f64::NAN, 1.0, 1.0), 8).is_err());
        assert!(GridSpec::fit(DVec3::ONE, DVec3::ZERO, 8).is_err());
        assert!(GridSpec::fit(DVec3::ZERO, DVec3::ONE, 0).is_err());
        assert!(GridSpec::fit(DVec3::ZERO, DVec3::ONE, GridSpec::MAX_DIM + 1).is_err());
    }

    #[test]
    fn flat_bounds_get_one_voxel_thick_axes() {
        let g = GridSpec::fit(DVec3::ZERO, DVec3::new(1.0, 0.0, 1.0), 16).unwrap();
        assert_eq!(g.dims, UVec3::new(16, 1, 16));
    }

    #[test]
    fn voxel_of_follows_half_open_convention() {
        let g = GridSpec::new(DVec3::ZERO, 0.5, UVec3::splat(4)).unwrap();
        assert_eq!(g.voxel_of(DVec3::splat(0.5)), Some(UVec3::ONE));
        assert_eq!(g.voxel_of(DVec3::splat(0.4999)), Some(UVec3::ZERO));
        assert_eq!(g.voxel_of(DVec3::splat(2.0)), None);
        assert_eq!(g.voxel_center(UVec3::ZERO), DVec3::splat(0.25));
    }
}
