//! The orbit camera of the 3D view and the headless renderer: z up, right-handed, wgpu clip space
//! (depth 0..1).

use glam::{Mat4, Vec2, Vec3};

/// A camera orbiting a target point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target_world: Vec3,
    /// Angle about world z, radians (0 looks along +y from −y).
    pub yaw_rad: f32,
    /// Elevation above the horizontal, radians.
    pub pitch_rad: f32,
    pub distance_m: f32,
    pub fov_y_rad: f32,
}

/// Named viewpoints for `partscene render --view` and the view menu.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewPreset {
    /// From the front-left, above.
    Iso,
    Front,
    Side,
    Top,
}

impl ViewPreset {
    pub const ALL: [ViewPreset; 4] = [ViewPreset::Iso, ViewPreset::Front, ViewPreset::Side, ViewPreset::Top];

    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ViewPreset::Iso => "iso",
            ViewPreset::Front => "front",
            ViewPreset::Side => "side",
            ViewPreset::Top => "top",
        }
    }

    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|v| v.name() == name)
    }

    fn angles_rad(self) -> (f32, f32) {
        match self {
            ViewPreset::Iso => (-0.6, 0.55),
            ViewPreset::Front => (0.0, 0.12),
            ViewPreset::Side => (std::f32::consts::FRAC_PI_2, 0.12),
            ViewPreset::Top => (0.0, 1.55),
        }
    }
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self { target_world: Vec3::ZERO, yaw_rad: -0.6, pitch_rad: 0.55, distance_m: 8.0, fov_y_rad: 45f32.to_radians() }
    }
}

const MIN_PITCH_RAD: f32 = -1.55;
const MAX_PITCH_RAD: f32 = 1.55;

impl OrbitCamera {
    /// A camera from `preset` that frames the box `[lo, hi]`.
    #[must_use]
    pub fn framing(lo: Vec3, hi: Vec3, preset: ViewPreset) -> Self {
        let (yaw_rad, pitch_rad) = preset.angles_rad();
        let mut cam = Self { yaw_rad, pitch_rad, ..Self::default() };
        cam.frame(lo, hi);
        cam
    }

    /// Keeps the direction and moves so that the box `[lo, hi]` fills the view.
    pub fn frame(&mut self, lo: Vec3, hi: Vec3) {
        if !(lo.is_finite() && hi.is_finite()) || lo.cmpgt(hi).any() {
            return;
        }
        self.target_world = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(0.05);
        // The bounding sphere is conservative for boxes: 0.8 of its fit fills the view well.
        self.distance_m = radius / (0.5 * self.fov_y_rad).sin() * 0.8;
    }

    /// Unit vector from the target to the eye.
    #[must_use]
    pub fn backward(&self) -> Vec3 {
        let (sy, cy) = self.yaw_rad.sin_cos();
        let (sp, cp) = self.pitch_rad.sin_cos();
        Vec3::new(sy * cp, -cy * cp, sp)
    }

    #[must_use]
    pub fn eye_world(&self) -> Vec3 {
        self.target_world + self.backward() * self.distance_m
    }

    /// Right and up directions of the image, in world coordinates.
    #[must_use]
    pub fn right_up(&self) -> (Vec3, Vec3) {
        let back = self.backward();
        let right = Vec3::Z.cross(back).try_normalize().unwrap_or(Vec3::X);
        (right, back.cross(right))
    }

    #[must_use]
    pub fn view_from_world(&self) -> Mat4 {
        let (_, up) = self.right_up();
        glam::camera::rh::view::look_at_mat4(self.eye_world(), self.target_world, up)
    }

    #[must_use]
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        let near = (self.distance_m * 0.01).max(0.005);
        let far = self.distance_m * 20.0 + 50.0;
        glam::camera::rh::proj::directx::perspective(self.fov_y_rad, aspect.max(1e-3), near, far)
    }

    #[must_use]
    pub fn clip_from_world(&self, aspect: f32) -> Mat4 {
        self.clip_from_view(aspect) * self.view_from_world()
    }

    /// Turns the camera by a drag of `delta` (fractions of the view height).
    pub fn orbit(&mut self, delta: Vec2) {
        self.yaw_rad -= delta.x * std::f32::consts::PI;
        self.pitch_rad = (self.pitch_rad + delta.y * std::f32::consts::PI).clamp(MIN_PITCH_RAD, MAX_PITCH_RAD);
    }

    /// Moves the target in the image plane by `delta` (fractions of the view height).
    pub fn pan(&mut self, delta: Vec2) {
        let (right, up) = self.right_up();
        let scale = 2.0 * self.distance_m * (0.5 * self.fov_y_rad).tan();
        self.target_world += (-delta.x * right + delta.y * up) * scale;
    }

    /// Zooms by `factor` (> 1 moves closer).
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.distance_m = (self.distance_m / factor).clamp(0.05, 500.0);
        }
    }

    /// The world ray through a point of the view, given in normalised device coordinates
    /// (x right, y up, both in −1..1). Returns (origin, unit direction).
    #[must_use]
    pub fn ray(&self, ndc: Vec2, aspect: f32) -> (Vec3, Vec3) {
        let world_from_clip = self.clip_from_world(aspect).inverse();
        let near = world_from_clip.project_point3(ndc.extend(0.0));
        let far = world_from_clip.project_point3(ndc.extend(1.0));
        (near, (far - near).normalize_or(-self.backward()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ray_through_the_centre_hits_the_target_and_framing_sees_the_whole_box() {
        let cam = OrbitCamera::framing(Vec3::new(-1.0, -2.0, 0.0), Vec3::new(3.0, 2.0, 2.0), ViewPreset::Iso);
        let (origin, dir) = cam.ray(Vec2::ZERO, 1.5);
        let to_target = cam.target_world - origin;
        assert!(to_target.cross(dir).length() < 1e-3 * to_target.length(), "centre ray misses the target");
        // Every corner in front of the camera and near the view; the box fills a good part of it.
        let mut widest = 0f32;
        for x in [-1.0, 3.0] {
            for y in [-2.0, 2.0] {
                for z in [0.0, 2.0] {
                    let clip = cam.clip_from_world(1.5).project_point3(Vec3::new(x, y, z));
                    assert!(clip.x.abs() <= 1.3 && clip.y.abs() <= 1.3 && (0.0..=1.0).contains(&clip.z), "({x}, {y}, {z}) → {clip}");
                    widest = widest.max(clip.x.abs().max(clip.y.abs()));
                }
            }
        }
        assert!(widest > 0.6, "the box fills too little of the view: {widest}");
    }

    #[test]
    fn orbit_keeps_the_distance_and_pitch_stays_below_the_pole() {
        let mut cam = OrbitCamera::default();
        cam.orbit(Vec2::new(0.3, 5.0));
        assert!(cam.pitch_rad <= MAX_PITCH_RAD);
        assert!(((cam.eye_world() - cam.target_world).length() - cam.distance_m).abs() < 1e-4);
    }
}
