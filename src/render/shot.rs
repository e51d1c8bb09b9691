//! `partscene render`: a picture of a scene file without a window.

use std::collections::BTreeMap;
use std::path::Path;

use image::RgbaImage;

use super::camera::{OrbitCamera, ViewPreset};
use super::draw::{DrawOptions, SceneView, scene_draw_data};
use super::offscreen::{Headless, RenderError};
use crate::edit::{Document, EditError, SceneSource};
use crate::export::read_scene_json;
use crate::model::SceneModel;
use crate::pipeline::{PinnedEdits, PipelineConfig, Quiet};
use crate::scan::Scan;

/// How to take the picture.
#[derive(Clone, Debug)]
pub struct ShotOptions {
    pub view: ViewPreset,
    pub size_px: [u32; 2],
    pub draw: DrawOptions,
    /// Every movable joint opened to this fraction of the way from rest (0) to the end of its
    /// travel farther from rest.
    pub open_fraction: f32,
}

impl Default for ShotOptions {
    fn default() -> Self {
        Self { view: ViewPreset::Iso, size_px: [1280, 800], draw: DrawOptions::default(), open_fraction: 0.0 }
    }
}

/// Why a shot could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum ShotError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Open(#[from] EditError),
    #[error("{path}: expected a scene.json, a session (.json), a scan (.ply or .npz) or `demo`: {message}")]
    Input { path: String, message: String },
}

/// A scene to draw: the model, and the scan when there is one.
enum Loaded {
    Model(Box<SceneModel>),
    Document(Box<Document>),
}

fn load(input: &Path, config: &PipelineConfig) -> Result<Loaded, ShotError> {
    if input.as_os_str() == "demo" {
        let doc = Document::open(SceneSource::Demo { seed: 0, clean: false }, config.clone(), PinnedEdits::default(), &Quiet)?;
        return Ok(Loaded::Document(Box::new(doc)));
    }
    let ext = input.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    match ext.as_str() {
        "ply" | "npz" => {
            let doc = Document::open(SceneSource::Scan { path: input.to_owned() }, config.clone(), PinnedEdits::default(), &Quiet)?;
            Ok(Loaded::Document(Box::new(doc)))
        }
        "json" => match read_scene_json(input) {
            Ok(model) => Ok(Loaded::Model(Box::new(model))),
            Err(scene_err) => match Document::open_session(input, config.clone(), &Quiet) {
                Ok(doc) => Ok(Loaded::Document(Box::new(doc))),
                Err(session_err) => Err(ShotError::Input {
                    path: input.display().to_string(),
                    message: format!("as a scene: {scene_err}; as a session: {session_err}"),
                }),
            },
        },
        _ => Err(ShotError::Input { path: input.display().to_string(), message: format!("unknown extension {ext:?}") }),
    }
}

/// Renders `input` offscreen. Returns the image and the GPU adapter used.
pub fn render_file(input: &Path, options: &ShotOptions, config: &PipelineConfig) -> Result<(RgbaImage, String), ShotError> {
    let loaded = load(input, config)?;
    let (model, scan): (&SceneModel, Option<&Scan>) = match &loaded {
        Loaded::Model(m) => (&**m, None),
        Loaded::Document(d) => (d.model(), Some(d.scan())),
    };
    let gpu = Headless::new()?;
    let image = render_model(&gpu, model, scan, options)?;
    Ok((image, gpu.adapter))
}

/// Renders a scene (and its scan's points, if given) on `gpu`.
pub fn render_model(gpu: &Headless, model: &SceneModel, scan: Option<&Scan>, options: &ShotOptions) -> Result<RgbaImage, RenderError> {
    let f = options.open_fraction;
    // From rest (0) towards the end of travel farther from it: limits may be [0, u] or [-u, 0].
    let joint_q: BTreeMap<_, _> = model
        .joints
        .iter()
        .filter(|j| j.kind.is_movable() && f != 0.0)
        .map(|j| (j.child, f * if j.upper.abs() >= j.lower.abs() { j.upper } else { j.lower }))
        .collect();
    let motions = crate::kinematics::part_motions(&model.joints, &joint_q);
    let view = SceneView { model, scan, motions: &motions, selected: None, hovered: None };
    let data = scene_draw_data(&view, &options.draw);
    let camera = data.bounds.map_or_else(OrbitCamera::default, |(lo, hi)| OrbitCamera::framing(lo, hi, options.view));
    gpu.render(&data, &camera, options.size_px, 1.6)
}
