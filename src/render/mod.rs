//! The 3D view of a scene: camera, unit meshes and draw data (plain data), and the wgpu renderer
//! that draws them, inside the editor (blitted into egui's pass) or headless (`partscene render`).
//! Uses wgpu but not egui; feature `gui`.

mod camera;
mod draw;
mod gpu;
mod mesh;
mod offscreen;
mod shot;

pub use camera::{OrbitCamera, ViewPreset};
pub use draw::{
    DrawData, DrawOptions, FIT_ERROR_FULL_SCALE_M, LineVertex, PointColors, PointInstance, SceneView, SolidBatches, SolidInstance,
    error_color, part_color, pick_part, posed_primitive, scene_draw_data, scene_geometry, scene_points,
};
pub use gpu::{BACKGROUND, FrameParams, SceneRenderer, VIEW_FORMAT};
pub use mesh::{Mesh, MeshVertex, unit_cube, unit_cylinder, unit_sphere};
pub use offscreen::{Headless, RenderError, save_png};
pub use shot::{ShotError, ShotOptions, render_file, render_model};
