//! Cameras: the map (orthographic, straight down), the orbit overview (perspective from above and aside) and the
//! eye (perspective from a viewpoint with yaw, pitch and field of view).
//!
//! All cameras work in the terrain's local f32 frame (x east, y north, z up, origin subtracted) and produce a
//! reversed-Z clip transform (near plane at depth 1, far at 0, compared with `GreaterEqual`) so that a
//! `Depth32Float` buffer keeps precision over kilometres of terrain. Angles follow the culler: yaw is an azimuth
//! counter-clockwise from +x (east), pitch is up from the horizontal.

use glam::camera::rh::proj::directx::{orthographic, perspective_infinite_reverse};
use glam::camera::rh::view::look_to_mat4;
use glam::{Mat4, Vec2, Vec3};

/// Direction of a yaw/pitch pair (radians), as a unit vector.
pub fn direction(yaw: f32, pitch: f32) -> Vec3 {
    Vec3::new(pitch.cos() * yaw.cos(), pitch.cos() * yaw.sin(), pitch.sin())
}

/// Vertical field of view (radians) for a horizontal one at an aspect ratio (width / height).
pub fn vertical_fov(hfov: f32, aspect: f32) -> f32 {
    2.0 * ((hfov * 0.5).tan() / aspect.max(1e-6)).atan()
}

/// The widest horizontal field of view a perspective render shows; wider culling fields are drawn at this width.
pub const MAX_RENDER_HFOV_DEG: f32 = 150.0;

/// The most an [`EyeCamera`] is pitched up or down (radians), short of looking straight up or down.
pub const MAX_EYE_PITCH: f32 = 1.55;

/// The horizontal field of view (degrees, in `(0, 360]`) that a culler must keep around the yaw of an [`EyeCamera`]
/// drawn with the field `hfov_deg` (as the viewer draws it: at most [`MAX_RENDER_HFOV_DEG`]), pitched by `pitch_deg`,
/// into an image of aspect `aspect` (width / height): every pixel's azimuth lies within half of it of the yaw. Pitched,
/// an image reaches further round than its field at the corners on the side it tilts toward: with `t_h = tan(h/2)` and
/// `t_v = t_h / aspect`, the pixel `(a t_h, b t_v)` (`a, b` in `[−1, 1]`) looks along `f + a t_h r + b t_v u` (forward
/// `f`, right `r`, up `u`), whose horizontal part is `cos p − b t_v sin p` forward and `a t_h` aside: its azimuth from
/// the yaw is `atan(|a| t_h / (cos p − b t_v sin p))`, largest at a corner, `atan(t_h / (cos p − t_v |sin p|))`. Where
/// that denominator is below 0.05 the image reaches the nadir or the zenith, or comes close enough that the f32
/// rounding of the render would matter: 360. The result is widened by far more than the f32 rounding of the render (a
/// relative 1e-4 and 0.01°), and is never narrower than `hfov_deg` itself (wider culling fields are drawn narrower).
pub fn culling_hfov_deg(hfov_deg: f64, pitch_deg: f64, aspect: f64) -> f64 {
    let drawn = hfov_deg.clamp(1.0, f64::from(MAX_RENDER_HFOV_DEG)).to_radians();
    let pitch = pitch_deg
        .to_radians()
        .clamp(-f64::from(MAX_EYE_PITCH), f64::from(MAX_EYE_PITCH));
    let t_h = (0.5 * drawn).tan();
    let t_v = t_h / aspect.max(1e-6);
    let forward = pitch.cos() - t_v * pitch.sin().abs();
    // NaN (a field or pitch not a number) looks all around too.
    if forward.is_nan() || forward < 0.05 || !hfov_deg.is_finite() {
        return 360.0;
    }
    let reach = 2.0 * (t_h / forward).atan().to_degrees();
    (reach * (1.0 + 1e-4) + 0.01).max(hfov_deg).min(360.0)
}

/// The top-down orthographic map of a box: x east to the right, y north up, the whole footprint in view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapView {
    /// Centre of the view (local x, y).
    pub centre: Vec2,
    /// Half width and half height of the view (m).
    pub half: Vec2,
    /// Lowest and highest z of the terrain (local).
    pub z_range: [f32; 2],
}

impl MapView {
    /// Fits the footprint of `[min, max]` into an image of aspect `aspect` (width / height), with a 2% margin.
    pub fn fit(min: [f32; 3], max: [f32; 3], aspect: f32) -> MapView {
        let size = Vec2::new(max[0] - min[0], max[1] - min[1]).max(Vec2::splat(1e-3));
        let aspect = aspect.max(1e-6);
        let half_w = (size.x * 0.5).max(size.y * 0.5 * aspect) * 1.02;
        MapView {
            centre: Vec2::new(min[0] + max[0], min[1] + max[1]) * 0.5,
            half: Vec2::new(half_w, half_w / aspect),
            z_range: [min[2], max[2]],
        }
    }

    /// The clip transform (reversed Z).
    pub fn view_proj(&self) -> Mat4 {
        let top = self.z_range[1] + 10.0;
        let depth = (self.z_range[1] - self.z_range[0]).max(1.0) + 20.0;
        let view = look_to_mat4(self.centre.extend(top), Vec3::NEG_Z, Vec3::Y);
        let h = self.half;
        orthographic(-h.x, h.x, -h.y, h.y, depth, 0.5) * view
    }

    /// Local x, y under pixel `(u, v)` of a `width × height` image (v down).
    pub fn pixel_to_local(&self, u: f32, v: f32, width: f32, height: f32) -> Vec2 {
        Vec2::new(
            self.centre.x + (u / width * 2.0 - 1.0) * self.half.x,
            self.centre.y + (1.0 - v / height * 2.0) * self.half.y,
        )
    }

    /// Pixel `(u, v)` of local `(x, y)` in a `width × height` image.
    pub fn local_to_pixel(&self, p: Vec2, width: f32, height: f32) -> Vec2 {
        let n = (p - self.centre) / self.half;
        Vec2::new((n.x + 1.0) * 0.5 * width, (1.0 - n.y) * 0.5 * height)
    }
}

/// A perspective camera circling a target: the oblique overview.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// The point looked at (local).
    pub target: Vec3,
    /// Azimuth of the view direction (radians).
    pub yaw: f32,
    /// Pitch of the view direction (radians; negative looks down).
    pub pitch: f32,
    /// Distance from the camera to the target.
    pub distance: f32,
    /// Vertical field of view (radians).
    pub fov_y: f32,
}

impl Orbit {
    /// An overview of `[min, max]` from the south-west, 35° down, looking north-east (or along `yaw`/`pitch`
    /// when given), as close as possible while the whole box stays in an image of aspect `aspect`.
    pub fn overview(min: [f32; 3], max: [f32; 3], aspect: f32, yaw: Option<f32>, pitch: Option<f32>) -> Orbit {
        let (lo, hi) = (Vec3::from(min), Vec3::from(max));
        let mut orbit = Orbit {
            target: (lo + hi) * 0.5,
            yaw: yaw.unwrap_or(45f32.to_radians()),
            pitch: pitch.unwrap_or(-35f32.to_radians()).clamp(-1.55, 1.55),
            distance: 1.0,
            fov_y: 40f32.to_radians(),
        };
        orbit.distance = orbit.fit_distance(lo, hi, aspect);
        orbit
    }

    /// The smallest distance from the target at which every corner of `[lo, hi]` is in view (5% margin).
    pub fn fit_distance(&self, lo: Vec3, hi: Vec3, aspect: f32) -> f32 {
        let f = direction(self.yaw, self.pitch);
        let r = f.cross(Vec3::Z).normalize_or(Vec3::X);
        let u = r.cross(f);
        let fov_y = self.effective_fov_y(aspect);
        let tan_y = (fov_y * 0.5).tan() * 0.95;
        let tan_x = tan_y * aspect.max(1e-6);
        let mut d: f32 = 1.0;
        for k in 0..8 {
            let corner = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ) - self.target;
            // The corner's depth in front of a camera at target − f·d is d + corner·f.
            let ahead = corner.dot(f);
            d = d
                .max(corner.dot(r).abs() / tan_x - ahead)
                .max(corner.dot(u).abs() / tan_y - ahead);
        }
        d
    }

    fn effective_fov_y(&self, aspect: f32) -> f32 {
        // Keep the whole scene in view at narrow aspect ratios too.
        if aspect < 1.0 {
            vertical_fov(self.fov_y, 1.0 / aspect).max(self.fov_y)
        } else {
            self.fov_y
        }
    }

    /// The camera position (local).
    pub fn eye(&self) -> Vec3 {
        self.target - direction(self.yaw, self.pitch) * self.distance
    }

    /// The clip transform for an image of aspect `aspect` (reversed Z).
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let view = look_to_mat4(self.eye(), direction(self.yaw, self.pitch), Vec3::Z);
        let near = (self.distance * 1e-3).max(0.05);
        perspective_infinite_reverse(self.effective_fov_y(aspect), aspect.max(1e-6), near) * view
    }
}

/// A perspective camera at a viewpoint: what an observer standing there sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeCamera {
    /// Position (local).
    pub position: Vec3,
    /// Azimuth of the view direction (radians).
    pub yaw: f32,
    /// Pitch of the view direction (radians).
    pub pitch: f32,
    /// Horizontal field of view (radians), drawn at most [`MAX_RENDER_HFOV_DEG`].
    pub hfov: f32,
}

impl EyeCamera {
    /// The clip transform for an image of aspect `aspect` (reversed Z, near plane 0.1 m, no far plane).
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let hfov = self.hfov.clamp(1f32.to_radians(), MAX_RENDER_HFOV_DEG.to_radians());
        let pitch = self.pitch.clamp(-MAX_EYE_PITCH, MAX_EYE_PITCH);
        let view = look_to_mat4(self.position, direction(self.yaw, pitch), Vec3::Z);
        perspective_infinite_reverse(vertical_fov(hfov, aspect), aspect.max(1e-6), 0.1) * view
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every pixel of an eye view (its corners, edges and inside, unprojected through the render's own clip
        /// transform) lies within half the culling field of the yaw.
        #[test]
        fn the_culling_field_holds_every_pixel(
            hfov in 1.0f64..200.0, pitch in -95.0f64..95.0, aspect in 0.2f64..5.0, yaw in -400.0f64..400.0,
        ) {
            let field = culling_hfov_deg(hfov, pitch, aspect);
            prop_assert!(field >= hfov.min(360.0) && field <= 360.0);
            if field < 360.0 {
                let cam = EyeCamera {
                    position: Vec3::new(100.0, -50.0, 20.0),
                    yaw: (yaw as f32).to_radians(),
                    pitch: (pitch as f32).to_radians(),
                    hfov: (hfov.min(f64::from(MAX_RENDER_HFOV_DEG)) as f32).to_radians(),
                };
                let inverse = cam.view_proj(aspect as f32).inverse();
                for i in 0..=8 {
                    for j in 0..=8 {
                        // Depth 1e-3 is 100 m away (near plane 0.1 m, reversed Z): far enough from the eye that the
                        // f32 unprojection does not blur the direction.
                        let ndc = Vec3::new(i as f32 / 4.0 - 1.0, j as f32 / 4.0 - 1.0, 1e-3);
                        let d = (inverse.project_point3(ndc) - cam.position).as_dvec3();
                        let off = (d.y.atan2(d.x).to_degrees() - yaw).rem_euclid(360.0);
                        let off = off.min(360.0 - off);
                        prop_assert!(off <= 0.5 * field, "pixel ({i}, {j}): {off}° off the yaw, field {field}°");
                    }
                }
            }
        }
    }

    #[test]
    fn a_level_view_culls_its_own_field() {
        for hfov in [1.0, 60.0, 90.0, 150.0] {
            let field = culling_hfov_deg(hfov, 0.0, 16.0 / 9.0);
            assert!(field >= hfov && field < hfov * 1.001 + 0.02, "{hfov}: {field}");
        }
        // Wider than drawn: the culler keeps the field asked for.
        assert_eq!(culling_hfov_deg(200.0, 0.0, 1.0), 200.0);
        // Looking down, the bottom corners reach further round; straight down, everything.
        assert!(culling_hfov_deg(90.0, -30.0, 16.0 / 9.0) > 119.0);
        assert_eq!(culling_hfov_deg(90.0, -80.0, 16.0 / 9.0), 360.0);
        assert_eq!(culling_hfov_deg(f64::NAN, 0.0, 1.0), 360.0);
    }
}
