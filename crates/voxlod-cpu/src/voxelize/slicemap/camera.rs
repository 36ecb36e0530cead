//! The slicemap's camera and the host-side preparation every backend shares: view transform,
//! clipping, projection to window coordinates and snapping to the sub-pixel lattice.
//!
//! # Window coordinates
//! Pixel `(x, y)` spans `[x, x+1) × [y, y+1)` from the top-left corner of the map, as in
//! [`voxlod_scene::camera::CameraFrame`]; its sample point is its centre `(x + ½, y + ½)`.
//! Perspective maps use the same projection as the scene camera (vertical field of view, the
//! horizontal one from the aspect ratio), so a [`voxlod_scene::Camera`] converts directly
//! ([`SliceCamera::from_camera`]).
//!
//! # Depth
//! A slice is defined by the **eye-space z** of a point: its distance along the view axis
//! `forward` from the plane through the eye, not its distance to the centre of projection. So
//! slices are planes (a cell is a frustum piece bounded by planes), an orthographic map aligned
//! with a grid reproduces the grid's layers, and z is exact under interpolation: `z` is affine
//! in window coordinates for an orthographic camera and `1/z` is affine for a perspective one,
//! so the depth parameter `q` ([`SliceCamera::q_of_z`]) interpolated linearly over a triangle's
//! window-space footprint gives the exact z of the triangle's point under a pixel centre (the
//! distance to the eye is not affine in either and would not be).
//!
//! # Preparation
//! [`prepare`] turns each triangle into the [`SliceTriangle`] records both backends rasterize:
//! view transform in `f64`; a perspective map clips at the near plane (so that no vertex is at
//! or behind the eye); both clip to the window grown by [`GUARD_PIXELS`] on every side (so
//! that snapped coordinates stay small and exact in `f32`; clipping outside the window changes
//! no pixel inside it); the clipped polygon is cut into a fan of triangles whose window
//! coordinates are snapped to `1/256` pixel ([`SUBPIXEL_BITS`] = 8, what GPU rasterizers do),
//! with `q` per vertex and its gradient over the snapped triangle. Triangles wholly nearer than
//! `near` or farther than `far` are culled. Orientation (front- or back-facing) is decided on
//! the unclipped world-space triangle: front-facing when its normal `(b − a) × (c − a)` points
//! toward the eye.

use bytemuck::{Pod, Zeroable};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use voxlod_scene::{Camera, Geometry};

use crate::{Error, Result};

/// Sub-pixel precision of the snapped window coordinates: `2^8` steps per pixel.
pub const SUBPIXEL_BITS: u32 = 8;
/// One pixel in sub-pixel units.
pub const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
/// Largest map side in pixels (the paper's largest viewport): snapped coordinates then stay
/// below `2^21` sub-pixel units, exact in `f32` and in the GPU's viewport transform.
pub const MAX_SIDE: u32 = 4096;
/// Pixels by which the clipping window exceeds the map on every side.
pub const GUARD_PIXELS: f64 = 2.0;

/// How the camera projects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Parallel columns covering `[-half_width, half_width] × [-half_height, half_height]`
    /// (world units) around the view axis.
    Orthographic {
        /// Half the map's extent along `right`.
        half_width: f64,
        /// Half the map's extent along `up`.
        half_height: f64,
    },
    /// Columns through the eye; vertical field of view in degrees, in (0, 180).
    Perspective {
        /// Vertical field of view in degrees.
        fov_y_deg: f64,
    },
}

/// The camera that defines a slicemap's columns and depth range (Eisemann and Décoret 2006,
/// §2.1): one column per pixel of a `width × height` viewport, depth from `near` to `far`
/// along the view axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceCamera {
    /// Eye position (for an orthographic map, the centre of the plane `z = 0`).
    pub eye: DVec3,
    /// View direction (normalized by the frame).
    pub forward: DVec3,
    /// Approximate up direction (orthogonalized against `forward`); window `y` grows along
    /// `−up`.
    pub up: DVec3,
    /// The projection.
    pub projection: Projection,
    /// Columns along x, 1..=[`MAX_SIDE`].
    pub width: u32,
    /// Columns along y, 1..=[`MAX_SIDE`].
    pub height: u32,
    /// Eye-space z of the first slice's near boundary (`> 0` for a perspective camera).
    pub near: f64,
    /// Eye-space z of the last slice's far boundary (`> near`).
    pub far: f64,
}

/// A [`SliceCamera`]'s orthonormal frame and projection scales.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceFrame {
    /// Eye position.
    pub eye: DVec3,
    /// Unit view direction.
    pub forward: DVec3,
    /// Unit right vector (window `+x`).
    pub right: DVec3,
    /// Unit up vector (window `−y`).
    pub up: DVec3,
    /// Whether the projection is perspective.
    pub perspective: bool,
    /// Orthographic: half extents; perspective: `tan(fov/2)·aspect` and `tan(fov/2)`.
    pub scale: DVec2,
    /// Map size in pixels.
    pub size: DVec2,
}

impl SliceCamera {
    /// A perspective map seen through a scene camera, `width × height` columns.
    pub fn from_camera(camera: &Camera, width: u32, height: u32, near: f64, far: f64) -> Self {
        SliceCamera {
            eye: camera.eye.as_dvec3(),
            forward: (camera.target - camera.eye).as_dvec3(),
            up: camera.up.as_dvec3(),
            projection: Projection::Perspective { fov_y_deg: camera.fov_y_deg as f64 },
            width,
            height,
            near,
            far,
        }
    }

    /// The orthographic map aligned with `grid` along `axis` (0, 1, 2 for x, y, z), voxel for
    /// voxel: window pixel `(x, y)` is the column of voxels whose index is `x` along axis
    /// `(axis + 1) % 3` and `y` along `(axis + 2) % 3`, and slice `k` (with
    /// `dims[axis]` slices) is voxel `k` along `axis`. The eye lies on the grid's near face.
    /// Errors on an axis over 2 or a grid side over [`MAX_SIDE`].
    pub fn aligned(grid: &voxlod_format::GridSpec, axis: usize) -> Result<Self> {
        if axis > 2 {
            return Err(Error::InvalidParameter {
                name: "slicemap axis",
                value: axis.to_string(),
                reason: "0, 1 or 2 (x, y, z)".into(),
            });
        }
        grid.validate()?;
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let e = |k: usize| DVec3::AXES[k];
        let extent = grid.dims.as_dvec3() * grid.voxel_size;
        let eye = grid.origin + e(u) * extent[u] * 0.5 + e(v) * extent[v] * 0.5;
        let camera = SliceCamera {
            eye,
            forward: e(axis),
            // right = forward × up must be +u: up = −v.
            up: -e(v),
            projection: Projection::Orthographic {
                half_width: extent[u] * 0.5,
                half_height: extent[v] * 0.5,
            },
            width: grid.dims[u],
            height: grid.dims[v],
            near: 0.0,
            far: extent[axis],
        };
        camera.validate()?;
        Ok(camera)
    }

    /// An orthographic map looking along `direction` that encloses the box `[lo, hi]` (grown by
    /// a thousandth of its extent) with columns of square pixels, `longest` columns along the
    /// longer side.
    pub fn enclosing_orthographic(direction: DVec3, lo: DVec3, hi: DVec3, longest: u32) -> Self {
        let forward = direction.normalize_or(DVec3::NEG_Z);
        let up0 = if forward.y.abs() > 0.99 { DVec3::Z } else { DVec3::Y };
        let right = forward.cross(up0).normalize();
        let up = right.cross(forward);
        let centre = (lo + hi) * 0.5;
        let half = (hi - lo) * 0.5;
        let reach = |a: DVec3| half.x * a.x.abs() + half.y * a.y.abs() + half.z * a.z.abs();
        // A margin of 1/1000 of the extent keeps near < far for flat scenes.
        let pad = 1e-3 * (reach(right) + reach(up) + reach(forward)) + 1e-30;
        let (hx, hy, hz) = (reach(right) + pad, reach(up) + pad, reach(forward) + pad);
        let longest = longest.clamp(1, MAX_SIDE);
        let (width, height) = if hx >= hy {
            (longest, ((longest as f64 * hy / hx).ceil() as u32).max(1))
        } else {
            (((longest as f64 * hx / hy).ceil() as u32).max(1), longest)
        };
        let pixel = if hx >= hy { 2.0 * hx / width as f64 } else { 2.0 * hy / height as f64 };
        SliceCamera {
            eye: centre,
            forward,
            up,
            projection: Projection::Orthographic {
                half_width: pixel * width as f64 * 0.5,
                half_height: pixel * height as f64 * 0.5,
            },
            width,
            height,
            near: -hz,
            far: hz,
        }
    }

    /// Checks that the camera defines a map: finite vectors, a view direction, `up` not
    /// parallel to it, sides in 1..=[`MAX_SIDE`], positive finite orthographic extents or a
    /// field of view in (0, 180), finite `near < far`, and `near > 0` for a perspective map.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, value: String, reason: &str| {
            Err(Error::InvalidParameter { name, value, reason: reason.into() })
        };
        if !(self.eye.is_finite() && self.forward.is_finite() && self.up.is_finite()) {
            return bad("slicemap camera", format!("{self:?}"), "eye, forward, up must be finite");
        }
        let f = self.forward.normalize_or_zero();
        if f == DVec3::ZERO {
            return bad("slicemap camera forward", format!("{}", self.forward), "is zero");
        }
        if f.cross(self.up).length_squared() < 1e-20 {
            return bad(
                "slicemap camera up",
                format!("{}", self.up),
                "is zero or parallel to the view direction",
            );
        }
        for (name, side) in [("slicemap width", self.width), ("slicemap height", self.height)] {
            if side == 0 || side > MAX_SIDE {
                return bad(name, side.to_string(), &format!("must be in 1..={MAX_SIDE} columns"));
            }
        }
        match self.projection {
            Projection::Orthographic { half_width, half_height } => {
                for v in [half_width, half_height] {
                    if !(v.is_finite() && v > 0.0) {
                        return bad(
                            "slicemap orthographic extent",
                            format!("{half_width} × {half_height}"),
                            "half extents must be positive and finite",
                        );
                    }
                }
            }
            Projection::Perspective { fov_y_deg } => {
                if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
                    return bad(
                        "slicemap fov",
                        fov_y_deg.to_string(),
                        "must be in (0, 180) degrees",
                    );
                }
                if self.near.is_nan() || self.near <= 0.0 {
                    return bad(
                        "slicemap near",
                        self.near.to_string(),
                        "a perspective map needs near > 0 (the near plane clips at the eye)",
                    );
                }
            }
        }
        if !(self.near.is_finite() && self.far.is_finite() && self.near < self.far) {
            return bad(
                "slicemap depth range",
                format!("near {} far {}", self.near, self.far),
                "needs finite near < far",
            );
        }
        // The depth range must survive rounding to f32, where the kernels work.
        if self.far as f32 - self.near as f32 <= 0.0 {
            return bad(
                "slicemap depth range",
                format!("near {} far {}", self.near, self.far),
                "near and far round to the same f32",
            );
        }
        Ok(())
    }

    /// The frame. Call [`SliceCamera::validate`] first: a degenerate camera gives NaNs.
    pub fn frame(&self) -> SliceFrame {
        let forward = self.forward.normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let size = DVec2::new(self.width as f64, self.height as f64);
        let (perspective, scale) = match self.projection {
            Projection::Orthographic { half_width, half_height } => {
                (false, DVec2::new(half_width, half_height))
            }
            Projection::Perspective { fov_y_deg } => {
                let t = (fov_y_deg.to_radians() * 0.5).tan();
                (true, DVec2::new(t * size.x / size.y, t))
            }
        };
        SliceFrame { eye: self.eye, forward, right, up, perspective, scale, size }
    }

    /// Whether the projection is perspective.
    pub fn is_perspective(&self) -> bool {
        matches!(self.projection, Projection::Perspective { .. })
    }

    /// The depth parameter the rasterizer interpolates for eye-space depth `z`: `z`
    /// (orthographic) or `1/z` (perspective).
    #[inline]
    pub fn q_of_z(&self, z: f64) -> f64 {
        if self.is_perspective() { 1.0 / z } else { z }
    }
}

impl SliceFrame {
    /// View coordinates `(x along right, y along up, z along forward)` of world point `p`.
    #[inline]
    pub fn to_view(&self, p: DVec3) -> DVec3 {
        let d = p - self.eye;
        DVec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.forward))
    }

    /// Window coordinates (pixels from the top-left) and depth parameter `q` of view point
    /// `v` (perspective: `v.z > 0` is the caller's business).
    #[inline]
    pub fn view_to_window(&self, v: DVec3) -> (DVec2, f64) {
        let (ndc, q) = if self.perspective {
            (DVec2::new(v.x, v.y) / (self.scale * v.z), 1.0 / v.z)
        } else {
            (DVec2::new(v.x, v.y) / self.scale, v.z)
        };
        (DVec2::new((ndc.x + 1.0) * 0.5 * self.size.x, (1.0 - ndc.y) * 0.5 * self.size.y), q)
    }

    /// Window coordinates and eye-space z of world point `p`; `None` at or behind the eye of a
    /// perspective camera.
    #[inline]
    pub fn project(&self, p: DVec3) -> Option<(DVec2, f64)> {
        let v = self.to_view(p);
        if self.perspective && (v.z.is_nan() || v.z <= 0.0) {
            return None;
        }
        Some((self.view_to_window(v).0, v.z))
    }

    /// The ray through window point `w` (pixels from the top-left): origin on the plane
    /// `z = 0` (the eye for a perspective camera) and unit direction.
    #[inline]
    pub fn ray(&self, w: DVec2) -> (DVec3, DVec3) {
        let ndc = DVec2::new(2.0 * w.x / self.size.x - 1.0, 1.0 - 2.0 * w.y / self.size.y);
        if self.perspective {
            let d = self.forward
                + self.right * (ndc.x * self.scale.x)
                + self.up * (ndc.y * self.scale.y);
            (self.eye, d.normalize())
        } else {
            let o =
                self.eye + self.right * (ndc.x * self.scale.x) + self.up * (ndc.y * self.scale.y);
            (o, self.forward)
        }
    }
}

/// One triangle as both backends rasterize it (mirrors WGSL `SliceTri`): snapped window
/// coordinates, the depth parameter per vertex, its gradient, orientation and source id.
///
/// Layout: `#[repr(C)]`, 52 bytes, `Pod`, uploaded as-is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct SliceTriangle {
    /// Window x of vertex 0 in sub-pixel units (`1/256` pixel).
    pub x0: i32,
    /// Window y of vertex 0 in sub-pixel units.
    pub y0: i32,
    /// Window x of vertex 1.
    pub x1: i32,
    /// Window y of vertex 1.
    pub y1: i32,
    /// Window x of vertex 2.
    pub x2: i32,
    /// Window y of vertex 2.
    pub y2: i32,
    /// Depth parameter `q` ([`SliceCamera::q_of_z`]) at vertex 0.
    pub q0: f32,
    /// `q` at vertex 1.
    pub q1: f32,
    /// `q` at vertex 2.
    pub q2: f32,
    /// `∂q/∂x` per pixel over the snapped triangle (0 if its snapped area is 0).
    pub dqdx: f32,
    /// `∂q/∂y` per pixel over the snapped triangle (0 if its snapped area is 0).
    pub dqdy: f32,
    /// Bit 0: front-facing (see the module docs).
    pub flags: u32,
    /// Index of the source triangle in the geometry.
    pub id: u32,
}

/// [`SliceTriangle::flags`] bit of a front-facing triangle.
pub const FRONT_FACING: u32 = 1;

impl SliceTriangle {
    /// Snapped vertex `i` in sub-pixel units.
    #[inline]
    pub fn vertex(&self, i: usize) -> (i64, i64) {
        match i {
            0 => (self.x0 as i64, self.y0 as i64),
            1 => (self.x1 as i64, self.y1 as i64),
            _ => (self.x2 as i64, self.y2 as i64),
        }
    }

    /// `q` at vertex `i`.
    #[inline]
    pub fn q(&self, i: usize) -> f32 {
        [self.q0, self.q1, self.q2][i]
    }

    /// Twice the signed area in sub-pixel units² (positive: clockwise on screen, y down).
    #[inline]
    pub fn area2(&self) -> i64 {
        let (a, b, c) = (self.vertex(0), self.vertex(1), self.vertex(2));
        (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1)
    }

    /// Whether the source triangle faces the eye.
    #[inline]
    pub fn is_front(&self) -> bool {
        self.flags & FRONT_FACING != 0
    }
}

/// What [`prepare`] produced.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Prepared {
    /// The records, in source order (a clipped triangle gives up to 6, consecutively).
    pub triangles: Vec<SliceTriangle>,
    /// Source triangles culled (wholly outside the depth range or the window).
    pub culled: usize,
    /// Source triangles that were clipped (at the near plane or the window's guard band).
    pub clipped: usize,
}

/// A polygon vertex during clipping: window position (or view position) and `q`.
#[derive(Clone, Copy, Debug)]
struct ClipVertex {
    p: DVec3,
}

/// Clips the convex polygon `poly` to `f(p) ≥ 0` for an affine `f` (Sutherland–Hodgman).
fn clip(poly: &[ClipVertex], f: impl Fn(DVec3) -> f64) -> Vec<ClipVertex> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (fa, fb) = (f(a.p), f(b.p));
        if fa >= 0.0 {
            out.push(a);
        }
        if (fa >= 0.0) != (fb >= 0.0) {
            let t = fa / (fa - fb);
            out.push(ClipVertex { p: a.p + (b.p - a.p) * t });
        }
    }
    out
}

/// Snaps a window coordinate to the sub-pixel lattice (round to nearest, ties up).
#[inline]
pub fn snap(w: f64) -> i32 {
    (w * SUBPIXEL as f64 + 0.5).floor() as i32
}

/// The record of a snapped triangle with per-vertex `q`.
fn record(v: [(i32, i32, f64); 3], flags: u32, id: u32) -> SliceTriangle {
    let mut t = SliceTriangle {
        x0: v[0].0,
        y0: v[0].1,
        x1: v[1].0,
        y1: v[1].1,
        x2: v[2].0,
        y2: v[2].1,
        q0: v[0].2 as f32,
        q1: v[1].2 as f32,
        q2: v[2].2 as f32,
        dqdx: 0.0,
        dqdy: 0.0,
        flags,
        id,
    };
    let area2 = t.area2();
    if area2 != 0 {
        let (ax, ay) = ((v[1].0 - v[0].0) as f64, (v[1].1 - v[0].1) as f64);
        let (bx, by) = ((v[2].0 - v[0].0) as f64, (v[2].1 - v[0].1) as f64);
        let (qa, qb) = (v[1].2 - v[0].2, v[2].2 - v[0].2);
        let s = SUBPIXEL as f64 / area2 as f64;
        t.dqdx = ((qa * by - qb * ay) * s) as f32;
        t.dqdy = ((ax * qb - bx * qa) * s) as f32;
    }
    t
}

/// Prepares `geometry` for rasterization into the map of `camera` (see the module docs).
/// Errors on an invalid camera, a non-finite vertex (naming it) or a vertex index out of range
/// (naming the triangle).
pub fn prepare(geometry: &Geometry, camera: &SliceCamera) -> Result<Prepared> {
    camera.validate()?;
    if let Some(i) = geometry.positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::Scene(voxlod_scene::Error::NonFinite {
            mesh: "geometry".into(),
            attribute: "position",
            vertex: i,
            value: geometry.positions[i].to_array(),
        }));
    }
    let n = geometry.positions.len();
    if let Some(t) = geometry.indices.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
        let index = *geometry.indices[t].iter().find(|&&i| i as usize >= n).expect("found");
        return Err(Error::Scene(voxlod_scene::Error::IndexOutOfRange {
            mesh: "geometry".into(),
            triangle: t,
            index,
            vertex_count: n,
        }));
    }
    if geometry.indices.len() as u64 > u32::MAX as u64 {
        return Err(Error::InvalidParameter {
            name: "geometry",
            value: format!("{} triangles", geometry.indices.len()),
            reason: "triangle ids are 32-bit: at most 2^32 − 1 triangles".into(),
        });
    }
    let frame = camera.frame();
    let (near, far) = (camera.near, camera.far);
    let g = GUARD_PIXELS;
    let (lo, hi) = (DVec2::splat(-g), frame.size + g);
    // (records, culled, clipped) per chunk, concatenated in order.
    let chunks: Vec<(Vec<SliceTriangle>, usize, usize)> = geometry
        .indices
        .par_chunks(4096)
        .enumerate()
        .map(|(c, chunk)| {
            let mut out = Vec::with_capacity(chunk.len());
            let (mut culled, mut clipped) = (0, 0);
            for (k, idx) in chunk.iter().enumerate() {
                let id = (c * 4096 + k) as u32;
                let w = idx.map(|i| geometry.positions[i as usize].as_dvec3());
                let v = w.map(|p| frame.to_view(p));
                let (zmin, zmax) = (v[0].z.min(v[1].z).min(v[2].z), v[0].z.max(v[1].z).max(v[2].z));
                if zmax < near || zmin > far {
                    culled += 1;
                    continue;
                }
                let n = (w[1] - w[0]).cross(w[2] - w[0]);
                let toward = if frame.perspective { w[0] - frame.eye } else { frame.forward };
                let flags = if n.dot(toward) < 0.0 { FRONT_FACING } else { 0 };
                let mut poly: Vec<ClipVertex> = v.iter().map(|&p| ClipVertex { p }).collect();
                let mut was_clipped = false;
                if frame.perspective && zmin < near {
                    poly = clip(&poly, |p| p.z - near);
                    was_clipped = true;
                }
                // To window space: (x, y, q); q is affine there, so clipping it linearly is exact.
                for c in &mut poly {
                    let (w, q) = frame.view_to_window(c.p);
                    c.p = DVec3::new(w.x, w.y, q);
                }
                let inside = |c: &ClipVertex| {
                    c.p.x >= lo.x && c.p.x <= hi.x && c.p.y >= lo.y && c.p.y <= hi.y
                };
                if !poly.iter().all(inside) {
                    was_clipped = true;
                    poly = clip(&poly, |p| p.x - lo.x);
                    poly = clip(&poly, |p| hi.x - p.x);
                    poly = clip(&poly, |p| p.y - lo.y);
                    poly = clip(&poly, |p| hi.y - p.y);
                }
                if poly.len() < 3 {
                    culled += 1;
                    continue;
                }
                clipped += was_clipped as usize;
                let s: Vec<(i32, i32, f64)> =
                    poly.iter().map(|c| (snap(c.p.x), snap(c.p.y), c.p.z)).collect();
                for i in 1..s.len() - 1 {
                    out.push(record([s[0], s[i], s[i + 1]], flags, id));
                }
            }
            (out, culled, clipped)
        })
        .collect();
    let mut prepared = Prepared::default();
    prepared.triangles.reserve(chunks.iter().map(|c| c.0.len()).sum());
    for (t, culled, clipped) in chunks {
        prepared.triangles.extend(t);
        prepared.culled += culled;
        prepared.clipped += clipped;
    }
    Ok(prepared)
}
