//! `partscene` command line: glue only. `anyhow` lives here.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use partscene::bench;
use partscene::eval::{self, Metrics};
use partscene::export::{UrdfConfig, read_scene_json, write_scene_files};
use partscene::io::atomic_write;
use partscene::model::SceneModel;
use partscene::observe::{NoObserver, Observer};
use partscene::pipeline::{PinnedEdits, PipelineConfig, Progress, reconstruct_observed};
use partscene::scan::{Scan, read_scan, write_scan};
use partscene::truth::GroundTruth;

#[derive(Parser)]
#[command(name = "partscene", version, about = "Part-level interactive scenes from segmented 3D scans")]
struct Cli {
    /// Machine-readable JSON on stdout instead of the human summary (no progress bars).
    #[arg(long, global = true)]
    json: bool,
    /// θa: minimum |cos| between contact plane normals.
    #[arg(long, global = true, value_name = "COS")]
    align_min: Option<f32>,
    /// θd: maximum distance between contact planes, metres.
    #[arg(long, global = true, value_name = "M")]
    dist_max: Option<f32>,
    /// θc: minimum contact ratio.
    #[arg(long, global = true, value_name = "RATIO")]
    contact_min: Option<f32>,
    /// A part vocabulary (TOML, the format of `assets/vocabulary.toml`) laid over the built-in
    /// one: classes of the same name are replaced, new classes are tried first.
    #[arg(long, global = true, value_name = "FILE.toml")]
    vocab: Option<PathBuf>,
    /// Log every pipeline stage (scan, primitives, contact graph, tree, refinement steps, joints,
    /// the URDF's link frames with the joints swept through their ranges) to this Rerun recording
    /// (`demo`, `reconstruct`); with `gap`, the recording, the model's and the fitted model's
    /// replays and their residuals per joint.
    #[cfg(feature = "rerun")]
    #[arg(long, global = true, value_name = "FILE.rrd")]
    rerun: Option<PathBuf>,
    /// Log every pipeline stage to a newly spawned Rerun viewer (needs `rerun` installed).
    #[cfg(feature = "rerun")]
    #[arg(long, global = true)]
    rerun_spawn: bool,
    /// Without a command: the viewer-editor on the demo room (with the `gui` feature), else the
    /// demo on the built-in room (seed 0), written to `out/demo`.
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Clone)]
enum Command {
    /// Open the viewer-editor on a scan (.ply or .npz), a saved session (.json) or the demo room.
    #[cfg(feature = "gui")]
    View {
        /// A part-segmented scan (.ply or .npz) or a saved session (.json); the demo room when absent.
        input: Option<PathBuf>,
        /// Demo room seed (without INPUT).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Demo room with the clean complete scan.
        #[arg(long)]
        clean: bool,
        /// Do not autosave edits for crash recovery.
        #[arg(long)]
        no_autosave: bool,
    },
    /// Render a scene to a PNG without a window (wgpu; lavapipe where there is no GPU).
    #[cfg(feature = "gui")]
    Render {
        /// scene.json, a session (.json), a scan (.ply or .npz, reconstructed first) or `demo`.
        scene: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// Viewpoint.
        #[arg(long, default_value = "iso", value_parser = ["iso", "front", "side", "top"])]
        view: String,
        #[arg(long, default_value_t = 1280)]
        width: u32,
        #[arg(long, default_value_t = 800)]
        height: u32,
        /// Colour scan points by fit error instead of by part.
        #[arg(long)]
        fit_error: bool,
        /// Open every movable joint this fraction of the way from rest to its farther limit (1 = fully open).
        #[arg(long, default_value_t = 0.0, value_name = "F")]
        open: f32,
    },
    /// Generate the built-in demo room, scan it virtually, reconstruct and evaluate it.
    Demo {
        /// Room seed (0 is the default demo).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Run this many consecutive seeds starting at --seed and report each and the total.
        #[arg(long, default_value_t = 1)]
        count: u64,
        /// Scan with the clean complete setting (all around, no noise) instead of a partial scan.
        #[arg(long)]
        clean: bool,
        /// Instead of the demo room, the benchmarks' open floor of furnished bays, with at least
        /// this many parts (`benches/` use 150).
        #[arg(long)]
        min_parts: Option<usize>,
        /// Write scan, ground truth, scene.urdf, scene.json and eval.json here
        /// (one sub-folder per seed when --count > 1).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Check URDF files as simulators read them: one tree, existing links, limits, axes, masses,
    /// inertias, geometry sizes; exits non-zero when a file has an error.
    CheckUrdf {
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Reconstruct many scans, in parallel, into one folder each, with a summary (batch.json,
    /// batch.md); a re-run skips the scans already done with the same inputs.
    Batch {
        /// Scan files, folders of scans, quoted glob patterns or .txt manifests (one path per line).
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        /// Scans at once (default: the number of cores).
        #[arg(long)]
        jobs: Option<usize>,
    },
    /// Reconstruct a part-segmented scan: a PLY, or a `NumPy` .npz (arrays `points`, `object_ids`,
    /// `part_ids`, optional `normals` and label arrays), with the labels JSON beside it.
    Reconstruct {
        scan: PathBuf,
        #[arg(long)]
        out: PathBuf,
    },
    /// Score a reconstruction against ground truth (and the object-level baseline when the scan is given).
    Eval {
        /// scene.json written by `reconstruct` or `demo`.
        #[arg(long)]
        scene: PathBuf,
        /// gt.json written by `demo` (or `scan-asset`).
        #[arg(long)]
        truth: PathBuf,
        /// The scan (.ply or .npz), to also run and score the object-level baseline.
        #[arg(long)]
        scan: Option<PathBuf>,
    },
    /// Scan an articulated asset (URDF / MJCF) virtually: writes NAME.ply, NAME.json (labels) and
    /// NAME.gt.json (ground truth for `eval`).
    ScanAsset {
        asset: PathBuf,
        /// The scan to write (PLY); labels and truth go beside it.
        #[arg(long)]
        out: PathBuf,
        /// The clean complete setting (all around, no noise: the paper's annotation input).
        #[arg(long)]
        clean: bool,
        /// Camera viewpoints (default: 8 partial, 24 clean).
        #[arg(long)]
        viewpoints: Option<usize>,
        /// Depth noise σ at 1 m range, metres (default 0.0015 partial, 0 clean).
        #[arg(long, value_name = "M")]
        noise: Option<f32>,
        /// Fraction of points near a part border that take the neighbour's label (segmentation bleed).
        #[arg(long, value_name = "F")]
        strays: Option<f32>,
        /// Fraction of points pushed off the surface as outliers.
        #[arg(long, value_name = "F")]
        outliers: Option<f32>,
        /// Image size in pixels, `WIDTHxHEIGHT`.
        #[arg(long, value_name = "WxH")]
        image: Option<String>,
        /// Which asset axis is up (default: +y for habitat assets listed in a MANIFEST.tsv, else z).
        #[arg(long, value_parser = ["y", "z"])]
        up: Option<String>,
        /// Object category (default: MANIFEST.tsv `category`, else from the file name).
        #[arg(long)]
        category: Option<String>,
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Convert a scan made by others into a part-segmented scan plus ground truth for `eval`.
    Import {
        #[command(subcommand)]
        source: ImportSource,
    },
    /// Write a scene as MJCF with the physics `partscene gap` fitted (damping, frictionloss,
    /// stiffness/springref, armature, narrowed ranges) on its joints.
    Mjcf(FittedExport),
    /// Write a scene as text USD (`UsdPhysics`, one articulation per object) with the physics
    /// `partscene gap` fitted: damping and springs as drives, Coulomb friction and armature on
    /// `PhysxJointAxisAPI`, narrowed limits. For Isaac Sim.
    Usd(FittedExport),
    /// Benchmark every asset under DIR: scan (partial and clean), reconstruct, score against the
    /// asset's own annotation and the object-level baseline; print the tables.
    Bench {
        dir: PathBuf,
        /// Also write the tables as markdown here.
        #[arg(long)]
        markdown: Option<PathBuf>,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Also write each object's reconstruction from the clean scan here, one folder per
        /// asset (`scene.urdf`, `scene.srdf`, `objects/`, `scene_objects.json`, ...), with the
        /// truth it was scored against (`gt.json`, same frame: `partscene eval` reads it).
        #[arg(long, value_name = "DIR")]
        export: Option<PathBuf>,
    },
    /// Reality gap: compare a recording of the real object with simulation of the model, locate
    /// mismatches, find and fit the missing physics; writes report.json, model.fitted.urdf,
    /// model.fitted.json and plot_<joint>.svg into --out.
    Gap {
        /// The URDF (default: the recording's `# model:` line, relative to the CSV).
        #[arg(long)]
        model: Option<PathBuf>,
        /// The recording: CSV (spec gap-recording.md), or ROS: an MCAP file or a rosbag2 folder
        /// (MCAP storage) with `sensor_msgs/msg/JointState` and/or TF (`tf2_msgs/msg/TFMessage`:
        /// the model's links as tracked poses); ROS recordings need --model.
        #[arg(long)]
        recording: PathBuf,
        /// The `JointState` topic of an MCAP recording (needed when it has several).
        #[arg(long)]
        topic: Option<String>,
        #[arg(long)]
        out: PathBuf,
    },
    /// Score the reality-gap analysis on a folder of cases with known answers (as `bench` scores
    /// objects): each sub-folder holds model.urdf, recording.csv and truth.json
    /// (`scripts/gap_suite.py`). Prints a per-case table and a summary.
    ///
    /// Scoring: per joint, the reported kinds against the truth's (`unknown` is an extra kind,
    /// and a false positive on joints where the truth has nothing); parameters within 25 % of the
    /// truth (positions: 25 % of max(|truth|, the joint's measured motion range)); held-out RMSE
    /// cut ≥ 5× on joints with effects; confidence calibration; truth within ±2σ. A case that fails
    /// to load or analyse counts as wrong.
    ///
    /// CI: the --require-* options make the command exit with status 1 (after printing) when the
    /// summary is below them; shares are fractions in [0, 1].
    GapBench {
        /// Folder of case folders (or one case folder).
        dir: PathBuf,
        /// Also write the tables as markdown here.
        #[arg(long, value_name = "FILE")]
        markdown: Option<PathBuf>,
        /// Fail when fewer than this share of cases has exactly the truth's kinds on every joint.
        #[arg(long, value_name = "F", visible_alias = "min-kinds-exact")]
        require_kinds_exact: Option<f64>,
        /// Fail when fewer than this share of cases has every effect joint located.
        #[arg(long, value_name = "F")]
        require_located: Option<f64>,
        /// Fail when fewer than this share of truth parameters is within 25 %.
        #[arg(long, value_name = "F")]
        require_params: Option<f64>,
        /// Fail when fewer than this share of cases with effects has a held-out cut ≥ 5× on every
        /// effect joint.
        #[arg(long, value_name = "F")]
        require_cut: Option<f64>,
        /// Fail when fewer than this share of compared parameters has the truth within ±2σ.
        #[arg(long, value_name = "F")]
        require_coverage: Option<f64>,
        /// Fail when any case without concealed effects reports an effect.
        #[arg(long)]
        require_null_clean: bool,
        /// Fail when there are more false positives than this over all cases.
        #[arg(long, value_name = "N")]
        max_false_positives: Option<usize>,
        /// Fail when any case cannot be loaded or analysed.
        #[arg(long)]
        require_no_errors: bool,
    },
    /// Multibody dynamics of a URDF at given states (checks against other libraries): inverse
    /// dynamics, mass matrix, bias efforts and forward dynamics, as JSON.
    Dynamics {
        /// The URDF (fixed root).
        #[arg(long)]
        model: PathBuf,
        /// `{"joints": [..], "gravity": [x, y, z], "states": [{"q", "qd", "qdd", "tau"}]}`.
        #[arg(long)]
        states: PathBuf,
        #[arg(long)]
        out: PathBuf,
    },
}

/// A scene exported with the physics `partscene gap` fitted on its joints.
#[derive(clap::Args, Clone, Debug)]
struct FittedExport {
    /// scene.json written by `reconstruct`, `demo` or the editor.
    #[arg(long)]
    scene: PathBuf,
    /// `model.fitted.json` or `report.json` written by `partscene gap` for that scene's URDF.
    #[arg(long)]
    effects: Option<PathBuf>,
    /// The file to write.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Subcommand, Clone)]
enum ImportSource {
    /// A `MultiScan` scan folder (`scene_xxxxx_xx/` with the annotated mesh `scene_xxxxx_xx.ply`
    /// and `scene_xxxxx_xx.annotations.json`): points drawn on the faces by area, per-point object
    /// and part ids, labels and truth joints. Writes `OUT/scan.ply`, `OUT/scan.json` and
    /// `OUT/gt.json`.
    Multiscan {
        dir: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// Points drawn on the mesh faces (area-weighted, deterministic for a seed).
        #[arg(long, default_value_t = partscene::import::multiscan::DEFAULT_POINTS)]
        points: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
}

/// indicatif bars on stderr, only on a terminal and not in --json mode.
struct Bars {
    bar: Option<ProgressBar>,
}

impl Bars {
    /// Counting `unit` (parts, assets), with the current item as the message.
    fn new(enabled: bool, unit: &str) -> Self {
        let bar = (enabled && std::io::IsTerminal::is_terminal(&std::io::stderr())).then(|| {
            let b = ProgressBar::new(0);
            let template = format!("{{msg:>16}} [{{bar:40}}] {{pos}}/{{len}} {unit} ({{elapsed}})");
            b.set_style(ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()).progress_chars("=> "));
            b
        });
        Self { bar }
    }

    /// Like [`Bars::new`], with the estimated time left.
    fn with_eta(enabled: bool, unit: &str) -> Self {
        let bars = Self::new(enabled, unit);
        if let Some(b) = &bars.bar {
            let template = format!("{{msg:>16}} [{{bar:40}}] {{pos}}/{{len}} {unit} ({{elapsed}}, {{eta}} left)");
            b.set_style(ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()).progress_chars("=> "));
        }
        bars
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

impl Progress for Bars {
    fn update(&self, stage: &str, done: usize, total: usize) {
        if let Some(b) = &self.bar {
            b.set_length(total as u64);
            b.set_position(done as u64);
            b.set_message(stage.to_owned());
        }
    }
}

/// Where the pipeline's stages are reported: a Rerun recording or viewer when asked for.
// Fallible only with the `rerun` feature.
#[cfg_attr(not(feature = "rerun"), allow(clippy::unnecessary_wraps))]
fn observer(cli: &Cli) -> Result<Box<dyn Observer>> {
    #[cfg(feature = "rerun")]
    {
        use partscene::observe::rerun::RerunObserver;
        if (cli.rerun.is_some() || cli.rerun_spawn) && matches!(cli.command, Some(Command::Demo { count, .. }) if count > 1) {
            anyhow::bail!("--rerun logs one room per recording: use it with --count 1");
        }
        if let Some(path) = &cli.rerun {
            return Ok(Box::new(RerunObserver::save(path)?));
        }
        if cli.rerun_spawn {
            return Ok(Box::new(RerunObserver::spawn()?));
        }
    }
    let _ = cli;
    Ok(Box::new(NoObserver))
}

/// The pipeline configuration with the command line's thresholds applied.
fn config(cli: &Cli) -> Result<PipelineConfig> {
    let mut cfg = PipelineConfig::default();
    let contact = &mut cfg.tree.contact;
    if let Some(v) = cli.align_min {
        anyhow::ensure!((0.0..=1.0).contains(&v), "--align-min must be a cosine in [0, 1], got {v}");
        contact.align_min = v;
    }
    if let Some(v) = cli.dist_max {
        anyhow::ensure!(v > 0.0 && v.is_finite(), "--dist-max must be a positive distance in metres, got {v}");
        contact.dist_max_m = v;
    }
    if let Some(v) = cli.contact_min {
        anyhow::ensure!((0.0..=1.0).contains(&v), "--contact-min must be a ratio in [0, 1], got {v}");
        contact.contact_min = v;
    }
    if let Some(path) = &cli.vocab {
        cfg.vocabulary = std::sync::Arc::new(cfg.vocabulary.extended_with_file(path)?);
    }
    Ok(cfg)
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    let cfg = config(&cli)?;
    #[cfg(feature = "gui")]
    let default = Command::View { input: None, seed: 0, clean: false, no_autosave: false };
    #[cfg(not(feature = "gui"))]
    let default = Command::Demo { seed: 0, count: 1, clean: false, min_parts: None, out: Some(PathBuf::from("out/demo")) };
    let command = cli.command.clone().unwrap_or(default);
    match command {
        #[cfg(feature = "gui")]
        Command::View { input, seed, clean, no_autosave } => view_cmd(input, seed, clean, no_autosave, cfg),
        #[cfg(feature = "gui")]
        Command::Render { scene, out, view, width, height, fit_error, open } => {
            render_cmd(&scene, &out, &view, [width, height], fit_error, open, &cfg, cli.json)
        }
        Command::Demo { seed, count, clean, min_parts, out } => {
            demo(DemoRooms { seed, count, clean, min_parts }, out.as_deref(), &cfg, cli.json, &*observer(&cli)?)
        }
        Command::Reconstruct { scan, out } => reconstruct_cmd(&scan, &out, &cfg, cli.json, &*observer(&cli)?),
        Command::Batch { inputs, out, jobs } => batch_cmd(&inputs, &out, jobs, &cfg, cli.json),
        Command::CheckUrdf { files } => check_urdf_cmd(&files, cli.json),
        Command::Eval { scene, truth, scan } => eval_cmd(&scene, &truth, scan.as_deref(), cli.json),
        Command::ScanAsset { asset, out, clean, viewpoints, noise, strays, outliers, image, up, category, seed } => {
            let mut scanner = bench::run::asset_scanner_config(clean);
            if let Some(v) = viewpoints {
                anyhow::ensure!(v > 0, "--viewpoints must be at least 1");
                scanner.viewpoints = v;
            }
            if let Some(v) = noise {
                anyhow::ensure!(v >= 0.0 && v.is_finite(), "--noise must be a non-negative distance in metres, got {v}");
                scanner.depth_noise_m = v;
            }
            if let Some(v) = strays {
                anyhow::ensure!((0.0..=1.0).contains(&v), "--strays must be a fraction in [0, 1], got {v}");
                scanner.stray_fraction = v;
            }
            if let Some(v) = outliers {
                anyhow::ensure!((0.0..=1.0).contains(&v), "--outliers must be a fraction in [0, 1], got {v}");
                scanner.outlier_fraction = v;
            }
            if let Some(size) = image {
                let parsed = size.split_once(['x', 'X']).and_then(|(w, h)| Some((w.parse::<usize>().ok()?, h.parse::<usize>().ok()?)));
                let Some((w, h)) = parsed.filter(|(w, h)| *w > 0 && *h > 0) else {
                    anyhow::bail!("--image must be WIDTHxHEIGHT (e.g. 320x240), got {size:?}");
                };
                (scanner.image_width, scanner.image_height) = (w, h);
            }
            scan_asset_cmd(&asset, &out, &scanner, up.as_deref(), category, seed, cli.json)
        }
        Command::Import { source: ImportSource::Multiscan { dir, out, points, seed } } => {
            import_multiscan_cmd(&dir, &out, points, seed, cli.json)
        }
        Command::Mjcf(args) => mjcf_cmd(&args),
        Command::Usd(args) => usd_cmd(&args),
        Command::Bench { dir, markdown, seed, export } => bench_cmd(&dir, markdown.as_deref(), seed, export, &cfg, cli.json),
        Command::Gap { model, recording, topic, out } => {
            let report = gap_cmd(model.as_deref(), &recording, topic.as_deref(), &out, cli.json)?;
            #[cfg(feature = "rerun")]
            {
                use partscene::observe::rerun::RerunObserver;
                let observer = match (&cli.rerun, cli.rerun_spawn) {
                    (Some(path), _) => Some(RerunObserver::save(path)?),
                    (None, true) => Some(RerunObserver::spawn()?),
                    (None, false) => None,
                };
                if let Some(observer) = observer {
                    observer.gap_report(&report);
                }
            }
            let _ = report;
            Ok(())
        }
        Command::GapBench {
            dir,
            markdown,
            require_kinds_exact,
            require_located,
            require_params,
            require_cut,
            require_coverage,
            require_null_clean,
            max_false_positives,
            require_no_errors,
        } => {
            let requirements = partscene::gap::bench::Requirements {
                kinds_exact: require_kinds_exact,
                located: require_located,
                params: require_params,
                cut: require_cut,
                coverage: require_coverage,
                null_clean: require_null_clean,
                max_false_positives,
                no_errors: require_no_errors,
            };
            gap_bench_cmd(&dir, markdown.as_deref(), &requirements, cli.json)
        }
        Command::Dynamics { model, states, out } => dynamics_cmd(&model, &states, &out),
    }
}

fn write_outputs(dir: &Path, scene: &SceneModel) -> Result<()> {
    write_scene_files(dir, scene, &UrdfConfig::default())?;
    Ok(())
}

fn print_warnings(scene: &SceneModel) {
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
}

fn summary(scene: &SceneModel, seconds: f64) -> String {
    let movable = scene.joints.iter().filter(|j| j.kind.is_movable()).count();
    format!(
        "{} objects, {} parts, {} joints ({movable} movable), {} contact edges, {} warnings, {:.2} s",
        scene.objects.len(),
        scene.parts.len(),
        scene.joints.len(),
        scene.contact_edges.len(),
        scene.warnings.len(),
        seconds
    )
}

fn reconstruct_cmd(scan_path: &Path, out: &Path, cfg: &PipelineConfig, json: bool, observer: &dyn Observer) -> Result<()> {
    let (scan, scan_warnings) = read_scan(scan_path)?;
    let bars = Bars::new(!json, "parts");
    let t = Instant::now();
    let mut scene = reconstruct_observed(&scan, cfg, &PinnedEdits::default(), &bars, observer);
    bars.finish();
    let secs = t.elapsed().as_secs_f64();
    scene.warnings.splice(0..0, scan_warnings);
    write_outputs(out, &scene)?;
    if json {
        println!(
            "{}",
            serde_json::json!({"out": out, "objects": scene.objects.len(), "parts": scene.parts.len(), "joints": scene.joints.len(), "warnings": scene.warnings, "seconds": secs})
        );
    } else {
        print_warnings(&scene);
        println!("{}: {}", scan_path.display(), summary(&scene, secs));
        println!("wrote {} and {}", out.join("scene.urdf").display(), out.join("scene.json").display());
    }
    Ok(())
}

fn check_urdf_cmd(files: &[PathBuf], json: bool) -> Result<()> {
    let mut failed = 0;
    let mut rows = Vec::new();
    for file in files {
        let c = partscene::export::check_urdf_file(file);
        failed += usize::from(!c.is_ok());
        if json {
            rows.push(serde_json::json!({"file": file, "ok": c.is_ok(), "links": c.links, "joints": c.joints, "root": c.root, "errors": c.errors, "warnings": c.warnings}));
            continue;
        }
        for w in &c.warnings {
            eprintln!("{}: warning: {w}", file.display());
        }
        for e in &c.errors {
            eprintln!("{}: error: {e}", file.display());
        }
        if c.is_ok() {
            println!("{}: ok ({} links, {} joints, root {})", file.display(), c.links, c.joints, c.root.as_deref().unwrap_or("-"));
        }
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    }
    anyhow::ensure!(failed == 0, "{failed} of {} URDF files have errors", files.len());
    Ok(())
}

fn batch_cmd(inputs: &[PathBuf], out: &Path, jobs: Option<usize>, cfg: &PipelineConfig, json: bool) -> Result<()> {
    use partscene::batch;
    let scans = batch::resolve_inputs(inputs)?;
    let bars = Bars::with_eta(!json, "scans");
    let run = || batch::run_batch(&scans, out, cfg, &|done, total, name| bars.update(name, done, total));
    let report = match jobs {
        Some(n) => {
            anyhow::ensure!(n > 0, "--jobs must be at least 1");
            rayon::ThreadPoolBuilder::new().num_threads(n).build()?.install(run)?
        }
        None => run()?,
    };
    bars.finish();
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.markdown());
        println!("wrote {} and {}", out.join("batch.json").display(), out.join("batch.md").display());
    }
    anyhow::ensure!(
        report.failed == 0,
        "{} of {} scans failed (the others are done): see {}",
        report.failed,
        report.scans.len(),
        out.join("batch.md").display()
    );
    Ok(())
}

fn read_truth(path: &Path) -> Result<GroundTruth> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: not a partscene gt.json", path.display()))
}

/// One evaluated run: part-level metrics and the object-level baseline's geometry on the same scan.
#[derive(serde::Serialize)]
struct Evaluated {
    seed: Option<u64>,
    part_level: Metrics,
    object_level: eval::BaselineMetrics,
}

fn evaluate_both(scene: &SceneModel, truth: &GroundTruth, scan: &Scan, seed: Option<u64>) -> Evaluated {
    Evaluated { seed, part_level: eval::evaluate(scene, truth), object_level: eval::evaluate_baseline(scan, truth) }
}

fn eval_cmd(scene_path: &Path, truth_path: &Path, scan_path: Option<&Path>, json: bool) -> Result<()> {
    let scene = read_scene_json(scene_path)?;
    let truth = read_truth(truth_path)?;
    let metrics = eval::evaluate(&scene, &truth);
    let baseline = match scan_path {
        Some(p) => Some(eval::evaluate_baseline(&read_scan(p)?.0, &truth)),
        None => None,
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&serde_json::json!({"part_level": metrics, "object_level": baseline}))?);
    } else {
        println!("{metrics}");
        if let Some(b) = baseline {
            println!("object-level baseline: {b}");
        }
    }
    Ok(())
}

/// Which generated rooms `partscene demo` reconstructs.
#[derive(Clone, Copy)]
struct DemoRooms {
    seed: u64,
    count: u64,
    clean: bool,
    /// The large open floor of `synth::large_scene` with at least this many parts.
    min_parts: Option<usize>,
}

impl DemoRooms {
    fn generate(&self, seed: u64) -> (partscene::truth::GroundTruth, partscene::scan::Scan) {
        use partscene::synth::{ScannerConfig, large_scene, scan};
        match self.min_parts {
            Some(n) => {
                let truth = large_scene(seed, n);
                let scanner = if self.clean { ScannerConfig::clean_complete() } else { ScannerConfig::default() };
                let mut scan = scan(&truth, &scanner, seed);
                scan.source = format!("large scene seed {seed}, at least {n} parts");
                (truth, scan)
            }
            None if self.clean => partscene::synth::demo_clean(seed),
            None => partscene::synth::demo(seed),
        }
    }
}

fn demo(rooms: DemoRooms, out: Option<&Path>, cfg: &PipelineConfig, json: bool, observer: &dyn Observer) -> Result<()> {
    let mut runs = Vec::new();
    let count = rooms.count;
    for s in rooms.seed..rooms.seed + count.max(1) {
        let t = Instant::now();
        let (truth, scan) = rooms.generate(s);
        let scan_secs = t.elapsed().as_secs_f64();
        let bars = Bars::new(!json, "parts");
        let t = Instant::now();
        let scene = reconstruct_observed(&scan, cfg, &PinnedEdits::default(), &bars, observer);
        bars.finish();
        let secs = t.elapsed().as_secs_f64();
        let evaluated = evaluate_both(&scene, &truth, &scan, Some(s));
        let dir = out.map(|dir| if count > 1 { dir.join(format!("seed-{s}")) } else { dir.to_path_buf() });
        if let Some(dir) = &dir {
            write_outputs(dir, &scene)?;
            write_scan(&scan, &dir.join("scan.ply"))?;
            atomic_write(&dir.join("gt.json"), serde_json::to_string_pretty(&truth)?.as_bytes())?;
            atomic_write(&dir.join("eval.json"), serde_json::to_string_pretty(&evaluated)?.as_bytes())?;
        }
        if !json {
            print_warnings(&scene);
            println!("seed {s}: {} points scanned in {scan_secs:.2} s; {}", scan.point_count(), summary(&scene, secs));
            println!("{}", evaluated.part_level);
            println!("object-level baseline: {}", evaluated.object_level);
            if let Some(dir) = &dir {
                println!(
                    "wrote scan.ply, scan.json, gt.json, scene.urdf, scene.json, scene.mjcf.xml, scene.glb, eval.json to {}",
                    dir.display()
                );
            }
            println!();
        }
        runs.push(evaluated);
    }
    let total = eval::aggregate(runs.iter().map(|r| (&r.part_level, &r.object_level)));
    if json {
        println!("{}", serde_json::to_string_pretty(&serde_json::json!({"runs": runs, "total": total}))?);
    } else if runs.len() > 1 {
        println!("over {} seeds:\n{total}", runs.len());
    }
    Ok(())
}

fn scan_asset_cmd(
    asset: &Path,
    out: &Path,
    scanner: &partscene::synth::ScannerConfig,
    up: Option<&str>,
    category: Option<String>,
    seed: u64,
    json: bool,
) -> Result<()> {
    let mut entry = bench::manifest_entry_for(asset).unwrap_or_else(|| bench::AssetEntry {
        name: asset.display().to_string(),
        path: asset.to_path_buf(),
        category: None,
        up: bench::UpAxis::Z,
    });
    match up {
        Some("y") => entry.up = bench::UpAxis::Y,
        Some(_) => entry.up = bench::UpAxis::Z,
        None => {}
    }
    if category.is_some() {
        entry.category = category;
    }
    let t = Instant::now();
    let (truth, scan, warnings) = bench::scan_asset(&entry, scanner, seed)?;
    let secs = t.elapsed().as_secs_f64();
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    write_scan(&scan, out)?;
    let gt_path = out.with_extension("gt.json");
    atomic_write(&gt_path, serde_json::to_string_pretty(&truth.truth)?.as_bytes())?;
    let object = &truth.truth.objects[0];
    let movable = object.joints.iter().filter(|j| j.kind.is_movable()).count();
    if json {
        println!(
            "{}",
            serde_json::json!({"scan": out, "truth": gt_path, "points": scan.point_count(), "parts": scan.parts.len(),
                "truth_parts": object.parts.len(), "movable_joints": movable, "warnings": warnings, "seconds": secs})
        );
    } else {
        for w in &warnings {
            eprintln!("warning: {w}");
        }
        let labels: Vec<String> = object.parts.iter().map(|p| format!("{}:{}", p.id, p.label)).collect();
        println!(
            "{}: {} ({}), {} parts [{}], {movable} movable joints; {} points on {} parts in {secs:.2} s",
            asset.display(),
            truth.truth.objects[0].category,
            if entry.up == bench::UpAxis::Y { "+y up" } else { "+z up" },
            object.parts.len(),
            labels.join(" "),
            scan.point_count(),
            scan.parts.len()
        );
        println!("wrote {}, {} and {}", out.display(), out.with_extension("json").display(), gt_path.display());
    }
    Ok(())
}

fn import_multiscan_cmd(dir: &Path, out: &Path, points: usize, seed: u64, json: bool) -> Result<()> {
    use partscene::import::multiscan::{MAX_POINTS, MultiScanOptions, import_multiscan, write_import};
    anyhow::ensure!((1..=MAX_POINTS).contains(&points), "--points must be between 1 and {MAX_POINTS}, got {points}");
    let t = Instant::now();
    let imported = import_multiscan(dir, MultiScanOptions { points, seed })?;
    let [scan_path, labels_path, gt_path] = write_import(&imported, out)?;
    let secs = t.elapsed().as_secs_f64();
    let truth = &imported.truth;
    let joints: usize = truth.objects.iter().map(|o| o.joints.len()).sum();
    let movable: usize = truth.objects.iter().flat_map(|o| &o.joints).filter(|j| j.kind.is_movable()).count();
    if json {
        println!(
            "{}",
            serde_json::json!({"scan": scan_path, "labels": labels_path, "truth": gt_path, "scan_id": imported.scan_id,
                "points": imported.scan.point_count(), "parts": imported.scan.parts.len(), "objects": truth.objects.len(),
                "joints": joints, "movable_joints": movable, "warnings": imported.warnings, "seconds": secs})
        );
    } else {
        for w in &imported.warnings {
            eprintln!("warning: {w}");
        }
        println!(
            "{} ({}): {} points on {} parts of {} objects ({} background), {joints} truth joints ({movable} movable) in {secs:.2} s",
            dir.display(),
            imported.scan_id,
            imported.scan.point_count(),
            imported.scan.parts.len(),
            truth.objects.len(),
            imported.scan.background.len()
        );
        println!("wrote {}, {} and {}", scan_path.display(), labels_path.display(), gt_path.display());
    }
    Ok(())
}

fn bench_cmd(
    dir: &Path,
    markdown: Option<&Path>,
    seed: u64,
    export_dir: Option<PathBuf>,
    pipeline: &PipelineConfig,
    json: bool,
) -> Result<()> {
    let cfg = bench::BenchConfig { pipeline: pipeline.clone(), seed, export_dir, ..bench::BenchConfig::default() };
    let bars = Bars::new(!json, "assets");
    let progress = |done: usize, total: usize, name: &str| bars.update(name, done, total);
    let report = bench::bench_dir(dir, &cfg, &progress)?;
    bars.finish();
    if let Some(path) = markdown {
        atomic_write(path, report.markdown().as_bytes())?;
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        for o in &report.objects {
            for w in &o.warnings {
                eprintln!("warning: {}: {w}", o.name);
            }
        }
        println!("{report}");
        if let Some(path) = markdown {
            println!("wrote {}", path.display());
        }
    }
    Ok(())
}

#[cfg(feature = "gui")]
fn view_cmd(input: Option<PathBuf>, seed: u64, clean: bool, no_autosave: bool, config: PipelineConfig) -> Result<()> {
    use partscene::app::{LaunchOptions, run};
    use partscene::edit::SceneSource;
    let mut launch = LaunchOptions { config, ..LaunchOptions::default() };
    if no_autosave {
        launch.autosave = None;
    }
    match input {
        Some(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")) => launch.session = Some(p),
        Some(path) => launch.source = Some(SceneSource::Scan { path }),
        None => launch.source = Some(SceneSource::Demo { seed, clean }),
    }
    run(launch).map_err(|e| anyhow::anyhow!("cannot open the editor window: {e}"))
}

#[cfg(feature = "gui")]
fn render_cmd(
    scene: &Path,
    out: &Path,
    view: &str,
    size_px: [u32; 2],
    fit_error: bool,
    open: f32,
    cfg: &PipelineConfig,
    json: bool,
) -> Result<()> {
    use partscene::render::{PointColors, ShotOptions, ViewPreset, render_file, save_png};
    anyhow::ensure!(size_px[0] > 0 && size_px[1] > 0, "--width and --height must be at least 1");
    anyhow::ensure!((0.0..=1.0).contains(&open), "--open must be a fraction in [0, 1], got {open}");
    let mut options = ShotOptions { size_px, ..ShotOptions::default() };
    options.view = ViewPreset::from_name(view).with_context(|| format!("unknown --view {view:?}"))?;
    if fit_error {
        options.draw.point_colors = PointColors::ByFitError;
    }
    options.open_fraction = open;
    let t = Instant::now();
    let (image, adapter) = render_file(scene, &options, cfg)?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    save_png(&image, out)?;
    if json {
        println!("{}", serde_json::json!({"out": out, "width": image.width(), "height": image.height(), "adapter": adapter}));
    } else {
        println!("rendered {} ({}×{}) on {adapter} in {:.2} s", out.display(), image.width(), image.height(), t.elapsed().as_secs_f64());
    }
    Ok(())
}

fn gap_cmd(model: Option<&Path>, recording: &Path, topic: Option<&str>, out: &Path, json: bool) -> Result<partscene::gap::GapReport> {
    use partscene::gap;
    let is_ros = recording.is_dir() || recording.extension().is_some_and(|e| e.eq_ignore_ascii_case("mcap"));
    anyhow::ensure!(
        topic.is_none() || is_ros,
        "--topic chooses among the topics of an .mcap recording or a rosbag2 folder; {} is neither",
        recording.display()
    );
    let (rec, model) = if is_ros {
        // A ROS recording names no model, and its TF frames are read as the model's links.
        let Some(model_path) = model else {
            anyhow::bail!("{}: a ROS recording names no model: give --model M.urdf", recording.display());
        };
        let model = gap::load_model(model_path)?;
        let frames = gap::mcap::TfFrames::of_model(&model);
        let csv = if recording.is_dir() {
            gap::mcap::rosbag_to_csv(recording, topic, Some(&frames))?
        } else {
            gap::mcap::mcap_to_csv(&partscene::io::read_bytes(recording)?, recording, topic, Some(&frames))?
        };
        (gap::parse_recording(&csv, recording)?, model)
    } else {
        let rec = gap::read_recording(recording)?;
        let model_path = match (model, rec.named_model_path()) {
            (Some(m), _) => m.to_path_buf(),
            (None, Some(named)) => named,
            (None, None) => anyhow::bail!("no --model given and {} has no `# model:` line", recording.display()),
        };
        let model = gap::load_model(&model_path)?;
        (rec, model)
    };
    let started = Instant::now();
    let report = gap::analyze(&model, &rec, &gap::GapConfig::default())?;
    gap::write_outputs(out, &model, &report)?;
    if json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("analysed {} in {:.2} s -> {}", recording.display(), started.elapsed().as_secs_f64(), out.display());
        for note in &report.notes {
            println!("note: {note}");
        }
        for m in &report.mismatches {
            println!("mismatch {} {:.2}-{:.2} s rmse {:.4}: {}", m.joint, m.t_start, m.t_end, m.rmse, m.description);
        }
        for e in &report.effects {
            println!("effect {} {} (confidence {:.2}): {}", e.joint, e.kind, e.confidence, e.description);
        }
        println!("rmse {:.5} -> {:.5}", report.fit.rmse_before, report.fit.rmse_after);
    }
    Ok(report)
}

fn gap_bench_cmd(dir: &Path, markdown: Option<&Path>, requirements: &partscene::gap::bench::Requirements, json: bool) -> Result<()> {
    use partscene::gap::{GapConfig, bench};
    let shares = [
        ("--require-kinds-exact", requirements.kinds_exact),
        ("--require-located", requirements.located),
        ("--require-params", requirements.params),
        ("--require-cut", requirements.cut),
        ("--require-coverage", requirements.coverage),
    ];
    for (flag, v) in shares {
        if let Some(v) = v {
            anyhow::ensure!((0.0..=1.0).contains(&v), "{flag} must be a fraction in [0, 1], got {v}");
        }
    }
    let bars = Bars::new(!json, "cases");
    let progress = |done: usize, total: usize, name: &str| bars.update(name, done, total);
    let report = bench::bench_dir(dir, &GapConfig::default(), &progress)?;
    bars.finish();
    if let Some(path) = markdown {
        atomic_write(path, report.markdown().as_bytes())?;
    }
    let unmet = requirements.unmet(&report.summary);
    if json {
        let mut value = serde_json::to_value(&report)?;
        if let Some(object) = value.as_object_mut() {
            object.insert("unmet_requirements".into(), serde_json::json!(unmet));
        }
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        print!("{report}");
        if let Some(path) = markdown {
            println!("wrote {}", path.display());
        }
    }
    anyhow::ensure!(unmet.is_empty(), "gap-bench below the required thresholds: {}", unmet.join("; "));
    Ok(())
}

/// States in the order of `joints` (names from the URDF).
#[derive(serde::Deserialize)]
struct DynamicsStates {
    joints: Vec<String>,
    #[serde(default = "default_gravity")]
    gravity: [f64; 3],
    states: Vec<DynamicsState>,
}

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

#[derive(serde::Deserialize)]
struct DynamicsState {
    q: Vec<f64>,
    #[serde(default)]
    qd: Vec<f64>,
    #[serde(default)]
    qdd: Vec<f64>,
    #[serde(default)]
    tau: Vec<f64>,
}

fn dynamics_cmd(model_path: &Path, states_path: &Path, out: &Path) -> Result<()> {
    let model = partscene::gap::load_model(model_path)?;
    let (tree, _) = model.multibody()?;
    let text = std::fs::read_to_string(states_path).with_context(|| format!("reading {}", states_path.display()))?;
    let input: DynamicsStates =
        serde_json::from_str(&text).with_context(|| format!("{}: expected joints, gravity, states", states_path.display()))?;
    let dof_names: Vec<&str> = model.dofs().into_iter().map(|j| model.joints[j].name.as_str()).collect();
    // Position of each of our coordinates in the caller's order.
    let mut from_caller = Vec::with_capacity(dof_names.len());
    for name in &dof_names {
        let Some(k) = input.joints.iter().position(|j| j == name) else {
            anyhow::bail!("{}: joint {name} of {} is missing from `joints`", states_path.display(), model_path.display());
        };
        from_caller.push(k);
    }
    let n = dof_names.len();
    let gravity = glam::DVec3::from_array(input.gravity);
    let ours = |v: &[f64]| -> Vec<f64> { from_caller.iter().map(|&k| v.get(k).copied().unwrap_or(0.0)).collect() };
    let theirs = |v: &[f64]| -> Vec<f64> {
        let mut out = vec![0.0; input.joints.len()];
        for (i, &k) in from_caller.iter().enumerate() {
            out[k] = v[i];
        }
        out
    };
    let mut results = Vec::with_capacity(input.states.len());
    for (index, s) in input.states.iter().enumerate() {
        let (q, qd, qdd, tau) = (ours(&s.q), ours(&s.qd), ours(&s.qdd), ours(&s.tau));
        let m = tree.mass_matrix(&q);
        let mass_matrix: Vec<Vec<f64>> =
            (0..input.joints.len()).map(|r| (0..input.joints.len()).map(|c| caller_entry(&m, n, &from_caller, r, c)).collect()).collect();
        let forward =
            tree.forward_dynamics(&q, &qd, &tau, gravity).with_context(|| format!("state {index}: the mass matrix is singular"))?;
        results.push(serde_json::json!({
            "tau": theirs(&tree.inverse_dynamics(&q, &qd, &qdd, gravity)),
            "mass_matrix": mass_matrix,
            "bias": theirs(&tree.bias(&q, &qd, gravity)),
            "qdd": theirs(&forward),
        }));
    }
    let json = serde_json::json!({ "joints": input.joints, "results": results });
    partscene::io::atomic_write(out, serde_json::to_string_pretty(&json)?.as_bytes())?;
    Ok(())
}

/// Entry (r, c) of the caller's matrix from ours (0 for names that are not coordinates here).
fn caller_entry(m: &[f64], n: usize, from_caller: &[usize], r: usize, c: usize) -> f64 {
    let (Some(i), Some(j)) = (from_caller.iter().position(|&k| k == r), from_caller.iter().position(|&k| k == c)) else { return 0.0 };
    m[i * n + j]
}

/// The scene of `scene_path` and the joint dynamics of the fitted effects in `effects` (none
/// without), their warnings printed.
fn scene_with_dynamics(scene_path: &Path, effects: Option<&Path>) -> Result<(SceneModel, partscene::export::DynamicsTable)> {
    use partscene::export::{DynamicsTable, dynamics_from_effects, read_fitted_effects};
    let scene = read_scene_json(scene_path)?;
    let dynamics = match effects {
        Some(path) => {
            let (table, warnings) = dynamics_from_effects(&scene, &UrdfConfig::default(), &read_fitted_effects(path)?);
            for w in warnings {
                eprintln!("warning: {w}");
            }
            table
        }
        None => DynamicsTable::new(),
    };
    Ok((scene, dynamics))
}

fn mjcf_cmd(args: &FittedExport) -> Result<()> {
    let (scene, dynamics) = scene_with_dynamics(&args.scene, args.effects.as_deref())?;
    atomic_write(&args.out, partscene::export::scene_mjcf(&scene, &UrdfConfig::default(), &dynamics)?.as_bytes())?;
    println!("wrote {} ({} joints with fitted dynamics)", args.out.display(), dynamics.len());
    Ok(())
}

fn usd_cmd(args: &FittedExport) -> Result<()> {
    let (scene, dynamics) = scene_with_dynamics(&args.scene, args.effects.as_deref())?;
    atomic_write(&args.out, partscene::export::scene_usda(&scene, &UrdfConfig::default(), &dynamics)?.as_bytes())?;
    println!("wrote {} ({} joints with fitted dynamics)", args.out.display(), dynamics.len());
    Ok(())
}
