//! `manylights render`.
mod knob_args;
mod outputs;
mod report;

use anyhow::{Context, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
pub use knob_args::KnobArgs;
use render_core::emission_rays::EmissionRays;
use render_core::estimator::DirectLighting;
use render_core::filter::PixelFilter;
use render_core::light_points::LightPoints;
use render_core::output::{FileSet, json_encoder};
use render_core::render::{
    BudgetClock, Engine, RenderResult, RenderSettings, TimeBudget, render_interruptible,
};
use render_core::sampler::Sampler;
use render_core::scene::Scene;
use render_core::splat::Reconstruction;
use samplers::StrategyOptions;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Args)]
pub struct RenderArgs {
    /// A glTF file (.gltf/.glb), a pbrt scene (.pbrt), a composition (.toml) or
    /// `builtin:NAME?key=value&...`.
    pub scene: String,
    #[command(flatten)]
    pub strategy: StrategyArgs,
    /// Samples per pixel (default 16; with --time-budget, the most to take, unlimited if not given).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Seed of every random number of the render: the same seed gives the same image, whatever
    /// the thread count.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The pixel filter, `NAME[:RADIUS]`: box (radius 0.5 by default), triangle (2), gaussian
    /// (1.5, sigma 0.5) or mitchell (2, B = C = 1/3), sampled by filter importance sampling.
    /// The scene file's own `PixelFilter` is used when this is not given.
    #[arg(long, value_parser = PixelFilter::parse)]
    pub filter: Option<PixelFilter>,
    /// How the filter makes pixels of samples: `sampled` (filter importance sampling, each
    /// sample in its own pixel; the default) or `splat` (pbrt-v3's weighted splatting into every
    /// pixel within the radius, which `--reproduce` implies).
    #[arg(long, value_parser = reconstruction_parser())]
    pub reconstruction: Option<Reconstruction>,
    /// Image width in pixels (default: the camera's).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels (default: the camera's).
    #[arg(long)]
    pub height: Option<u32>,
    /// Camera name (default: the scene's first camera).
    #[arg(long)]
    pub camera: Option<String>,
    /// Output EXR (linear RGB float). A JSON file with the same stem is written beside it.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write an sRGB PNG preview.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure of the PNG preview in stops (negative darkens: `--exposure -3`). Without it, the
    /// preview is exposed automatically (the 97th percentile of the luminance of the pixels that
    /// see no light maps to 0.9); the JSON records the exposure used.
    #[arg(long, allow_negative_numbers = true)]
    pub exposure: Option<f32>,
    /// Render until this many seconds are spent (checked before each work unit of 256 pixels).
    #[arg(long)]
    pub time_budget: Option<f64>,
    /// What --time-budget counts: wall time, or the process's CPU time per worker thread
    /// (fair equal-time comparisons on a machine shared with other jobs).
    #[arg(long, value_enum, default_value = "wall")]
    pub budget_clock: BudgetClockArg,
    /// Worker threads (default: one per CPU). The image does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// How camera samples go through shading: `batched` (a work unit's samples in phases
    /// together, their rays traced as streams, for the strategies that have a batched form)
    /// or `per-sample` (one camera sample at a time, every ray alone); the JSON's
    /// `engine_used` says which ran. The image does not depend on it (bit for bit, but where
    /// two primitives tie at a rounding edge: docs/notes/rays.md, "Ties").
    #[arg(long, value_enum, default_value = "batched")]
    pub engine: EngineArg,
    /// Also write the mask of pixels that see a light directly and the strategy's diagnostics.
    #[arg(long)]
    pub aux: bool,
    /// Print ray throughput, the CPU time per spp and the strategy's own counters per shading
    /// point (e.g. the method's clusters and BRDF-aware samples).
    #[arg(long)]
    pub stats: bool,
    /// No progress bar, scene-load warnings or summary line on stderr (errors are still printed).
    #[arg(long)]
    pub quiet: bool,
}

/// What determines the strategy a render uses: its name, its knobs, the sampler and the emission rays
/// (`manylights strategy` takes the same flags and prints them resolved).
#[derive(Args, Debug, Clone)]
pub struct StrategyArgs {
    /// The direct-lighting strategy (`manylights strategies` lists them).
    #[arg(long, default_value = "power+bsdf")]
    pub strategy: String,
    /// Where the samples' numbers come from: `independent` numbers per dimension,
    /// `stratified` (jittered, needs --spp), `sobol` (Owen-scrambled (0,2)-sequences per
    /// dimension pair), `lowdiscrepancy` (pbrt-v3's scrambled (0,2)-sequence, the default) or
    /// `zsobol` (pbrt-v4's: one sequence over the image in Morton order, needs --spp). A
    /// scene file's own `Sampler` is used when this is not given.
    #[arg(long, value_parser = sampler_parser())]
    pub sampler: Option<Sampler>,
    /// Camera rays per sample that gather the emission seen directly, at the pixels that may
    /// straddle a light's edge (every pixel in the first pass, then those near a light not yet
    /// seen to be fully inside one): 1 traces only the sample's own ray; more lowers the noise of
    /// a pixel's coverage of the lights, which light sampling never touches. Needs the sampled
    /// reconstruction. [default: the strategy's own, which `manylights strategies --json` lists;
    /// 1 under --reproduce]
    #[arg(long, value_parser = emission_rays_parser)]
    pub emission_rays: Option<u32>,
    /// How every technique draws the point on a triangle light: `area` (uniformly by area),
    /// `solid-angle` (uniformly in the solid angle the triangle subtends, Arvo 1995) or
    /// `solid-angle-warp` (that, warped towards the receiver's cosine, as pbrt-v4). Both
    /// solid-angle samplers fall back to area sampling below 3e-4 sr and above 6.22 sr. Spheres
    /// are always sampled in their cone.
    #[arg(long, value_parser = light_points_parser(), default_value = "area")]
    pub light_points: LightPoints,
    #[command(flatten)]
    pub knobs: KnobArgs,
}

impl StrategyArgs {
    /// The registered strategy `--strategy` names.
    pub fn strategy(&self) -> anyhow::Result<&'static samplers::Strategy> {
        Ok(samplers::registry::find(&self.strategy)?)
    }

    /// The strategy's options: the defaults with the knob flags given applied; a flag the
    /// strategy does not take is an error naming the ones it does.
    pub fn options(&self) -> anyhow::Result<StrategyOptions> {
        Ok(self.strategy()?.options(&self.knobs.given)?)
    }

    /// `--emission-rays`, or the strategy's default.
    pub fn emission_rays(&self) -> anyhow::Result<u32> {
        match self.emission_rays {
            Some(k) => Ok(k),
            None => Ok(self.strategy()?.default_emission_rays(&self.options()?)),
        }
    }

    /// The strategy's name, every parameter it renders with (defaults filled in) and the
    /// sampler flag (none: the scene file's, else `lowdiscrepancy`; the scene's choice is
    /// covered by its `scene_hash`): what the render's
    /// JSON records as `resolved_strategy`.
    pub fn resolved(&self) -> anyhow::Result<serde_json::Value> {
        let parameters = samplers::registry::resolved_parameters(&self.strategy, &self.options()?)?;
        let mut resolved = serde_json::json!({
            "strategy": self.strategy,
            "parameters": parameters,
            "sampler": self.sampler.map(Sampler::name),
            "emission_rays": self.emission_rays()?,
        });
        // Named only when it is not `area`, so that the cells and references keyed before the
        // flag existed (all under `area`) keep their keys; another sampler changes the key.
        if self.light_points != LightPoints::Area {
            resolved["light_points"] = self.light_points.name().into();
        }
        Ok(resolved)
    }
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum BudgetClockArg {
    Wall,
    Cpu,
}

/// `--engine`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EngineArg {
    Batched,
    PerSample,
}

/// The sampler a render uses, and why: `--sampler`, else the scene file's, else pbrt-v3's
/// `lowdiscrepancy` (under `--reproduce` and by default).
fn choose_sampler(
    flag: Option<Sampler>,
    scene: &render_core::scene::Scene,
    reproduce: bool,
) -> (Sampler, &'static str) {
    match (flag, scene.render_hints.sampler) {
        (Some(s), _) => (s, "--sampler"),
        (None, Some(s)) => (s, "scene file"),
        (None, None) if reproduce => (Sampler::LowDiscrepancy, "--reproduce"),
        // The samplers experiment (results/samplers, rerun at c353c0d): at equal time pbrt-v3's
        // lowdiscrepancy beat independent numbers by 1.33× (MIS adaptive) and 1.08× (E&K) in
        // geometric mean, Sobol by 1.21× / 1.03× (the run at ef738dd had them level and chose
        // Sobol); docs/notes/samplers.md.
        (None, None) => (Sampler::LowDiscrepancy, "default"),
    }
}

/// The reconstruction, and what chose it: the flag, `--reproduce` (the authors' pbrt-v3 film
/// splats) or the default.
fn choose_reconstruction(
    flag: Option<Reconstruction>,
    reproduce: bool,
) -> (Reconstruction, &'static str) {
    match flag {
        Some(r) => (r, "--reconstruction"),
        None if reproduce => (Reconstruction::Splat, "--reproduce"),
        None => (Reconstruction::Sampled, "default"),
    }
}

/// `--emission-rays`: a count in the range [`EmissionRays::new`] accepts.
fn emission_rays_parser(s: &str) -> Result<u32, String> {
    let k: u32 = s.parse().map_err(|e| format!("{e}"))?;
    EmissionRays::new(k).map(EmissionRays::get)
}

/// `--reconstruction`: the names of [`Reconstruction`], listed in `--help`.
fn reconstruction_parser() -> impl clap::builder::TypedValueParser<Value = Reconstruction> {
    use clap::builder::{PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(Reconstruction::ALL.map(Reconstruction::name))
        .map(|s| Reconstruction::parse(&s).expect("a listed name"))
}

/// `--light-points`: the names of [`LightPoints`], listed in `--help`.
fn light_points_parser() -> impl clap::builder::TypedValueParser<Value = LightPoints> {
    use clap::builder::{PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(LightPoints::ALL.map(LightPoints::name))
        .map(|s| LightPoints::parse(&s).expect("a listed name"))
}

/// `--sampler`: the names of [`Sampler`], listed in `--help`.
fn sampler_parser() -> impl clap::builder::TypedValueParser<Value = Sampler> {
    use clap::builder::{PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(Sampler::ALL.map(Sampler::name))
        .map(|s| Sampler::from_name(&s).expect("a listed name"))
}

/// Fails early, before loading anything, when the file `flag` names cannot be written: a
/// directory in its place, or a directory that is missing or read-only.
pub fn check_output_file(path: &Path, flag: &str) -> anyhow::Result<()> {
    outputs::not_a_directory(path, flag)?;
    check_writable(path)
}

/// Fails early, before a long render, when the output cannot be written.
fn check_writable(path: &Path) -> anyhow::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        bail!("output directory {} does not exist", dir.display());
    }
    let probe = dir.join(format!(".manylights-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .with_context(|| format!("output directory {} is not writable", dir.display()))?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// What chose the sampler, the filter and the reconstruction of a render.
struct Choices {
    sampler: (Sampler, &'static str),
    filter: (PixelFilter, &'static str),
    reconstruction: (Reconstruction, &'static str),
}

/// The flags' own checks, before anything is loaded (the outputs apart: [`check_outputs`]).
pub fn check_args(args: &RenderArgs) -> anyhow::Result<()> {
    if args.spp == Some(0) {
        bail!("--spp must be at least 1");
    }
    if let Some(t) = args.time_budget
        && !(t > 0.0 && t.is_finite())
    {
        bail!("--time-budget must be a positive number of seconds");
    }
    if args.threads == Some(0) {
        bail!("--threads must be at least 1");
    }
    if let Some(t) = args
        .threads
        .filter(|&t| t > render_core::render::MAX_THREADS)
    {
        bail!(
            "--threads {t} is more than the {} a render may ask for",
            render_core::render::MAX_THREADS
        );
    }
    if args.exposure.is_some_and(|e| !e.is_finite()) {
        bail!("--exposure must be a finite number of stops");
    }
    Ok(())
}

/// Flags given that change nothing in this render, each with why.
fn ignored_flags(args: &RenderArgs) -> Vec<&'static str> {
    let mut ignored = Vec::new();
    if args.exposure.is_some() && args.png.is_none() {
        ignored
            .push("--exposure sets the --png preview's brightness; without --png it does nothing");
    }
    if matches!(args.budget_clock, BudgetClockArg::Cpu) && args.time_budget.is_none() {
        ignored.push("--budget-clock says what --time-budget counts; without one it does nothing");
    }
    ignored
}

/// That the output files are named for what they hold and can be written, before a long
/// render.
fn check_outputs(args: &RenderArgs) -> anyhow::Result<()> {
    let preview = " (for a PNG preview add --png NAME.png)";
    check_extension(&args.out, ("--out", "an OpenEXR image", "exr"), preview)?;
    check_writable(&args.out)?;
    if let Some(p) = &args.png {
        check_extension(p, ("--png", "a PNG image", "png"), "")?;
        check_writable(p)?;
    }
    Ok(())
}

/// Refuses an output whose name does not end in `.ext` (any case): `flag` writes `what`
/// whatever the name says, and a viewer that trusts the name would fail on it.
pub fn check_extension(
    path: &Path,
    (flag, what, ext): (&str, &str, &str),
    hint: &str,
) -> anyhow::Result<()> {
    let ok = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(ext));
    if !ok {
        bail!(
            "{flag} {}: {flag} writes {what}, so its name must end in .{ext}{hint}",
            path.display()
        );
    }
    Ok(())
}

/// The sampler, filter and reconstruction: each flag, else the scene file's, else the default.
fn choose(args: &RenderArgs, scene: &Scene, reproduce: bool) -> Choices {
    let filter = match (&args.filter, &scene.render_hints.filter) {
        (Some(f), _) => (f.clone(), "--filter"),
        (None, Some(f)) => (f.clone(), "scene file"),
        (None, None) => (PixelFilter::default(), "default"),
    };
    Choices {
        sampler: choose_sampler(args.strategy.sampler, scene, reproduce),
        filter,
        reconstruction: choose_reconstruction(args.reconstruction, reproduce),
    }
}

/// The render's settings from the flags, the scene's camera and the choices; refuses a size
/// whose buffers would not fit in memory and emission rays under splatting.
fn settings(
    args: &RenderArgs,
    scene: &Scene,
    choices: &Choices,
    emission_rays: u32,
    aux_channels: usize,
) -> anyhow::Result<RenderSettings> {
    let mut camera = scene.camera(None)?;
    let width = args.width.unwrap_or(camera.width);
    let height = args.height.unwrap_or(camera.height);
    if width == 0 || height == 0 {
        bail!("--width and --height must be positive");
    }
    render_core::render::check_memory(width, height, aux_channels).map_err(anyhow::Error::msg)?;
    camera.width = width;
    camera.height = height;
    let (reconstruction, reconstruction_from) = choices.reconstruction;
    if emission_rays != EmissionRays::OFF.get() && reconstruction == Reconstruction::Splat {
        bail!(
            "--emission-rays {} ({}) needs the sampled reconstruction, but {reconstruction_from} \
             chose splatting: add --reconstruction sampled, or --emission-rays 1",
            emission_rays,
            if args.strategy.emission_rays.is_some() {
                "the flag"
            } else {
                "the strategy's default"
            }
        );
    }
    Ok(RenderSettings {
        width,
        height,
        spp: match (args.spp, args.time_budget) {
            (Some(n), _) => Some(n),
            (None, Some(_)) => None,
            (None, None) => Some(16),
        },
        seed: args.seed,
        time_budget: args.time_budget.map(|seconds| TimeBudget {
            seconds,
            clock: match args.budget_clock {
                BudgetClockArg::Wall => BudgetClock::Wall,
                BudgetClockArg::Cpu => BudgetClock::Cpu,
            },
        }),
        threads: args.threads,
        camera,
        sampler: choices.sampler.0,
        filter: choices.filter.0.clone(),
        reconstruction,
        emission_rays: EmissionRays::new(emission_rays).map_err(anyhow::Error::msg)?,
        engine: match args.engine {
            EngineArg::Batched => Engine::Batched,
            EngineArg::PerSample => Engine::PerSample,
        },
    })
}

/// Renders with a progress bar (in spp, or a spinner under a time budget) unless `--quiet`.
fn render_with_progress(
    args: &RenderArgs,
    scene: &Scene,
    strategy: &dyn DirectLighting,
    settings: &RenderSettings,
) -> anyhow::Result<RenderResult> {
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else if let Some(n) = settings.spp.filter(|_| args.time_budget.is_none()) {
        ProgressBar::new(n as u64)
    } else {
        ProgressBar::new_spinner()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} spp {msg}",
        )
        .unwrap_or(ProgressStyle::default_bar()),
    );
    let interrupt = interrupt_on_ctrl_c();
    let result = render_interruptible(
        scene,
        strategy,
        settings,
        &|_, spp_done| bar.set_position(spp_done as u64),
        &interrupt,
    )
    .map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();
    if result.interrupted {
        eprintln!(
            "warning: interrupted by Ctrl-C: the image holds the samples done, {} full passes{}{}",
            result.spp,
            match result.partial_pixels {
                0 => String::new(),
                n => format!(" and {n} pixels of one more"),
            },
            match settings.spp {
                Some(n) => format!(", of the {n} asked for"),
                None => String::new(),
            }
        );
    }
    if result.unsampled_pixels() > 0 {
        eprintln!(
            "warning: the time budget ran out inside the first pass: {} of {} pixels have no sample and are black",
            result.unsampled_pixels(),
            result.pixels.len()
        );
    }
    Ok(result)
}

/// A flag that Ctrl-C sets, so that the render ends as a spent time budget ends it and its
/// samples are written; a second Ctrl-C quits at once (exit code 130, nothing written).
fn interrupt_on_ctrl_c() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let set = flag.clone();
    let handler = move || {
        if set.swap(true, Ordering::Relaxed) {
            std::process::exit(130);
        }
        eprintln!(
            "\ninterrupted: finishing the work units under way to write the samples done \
             (Ctrl-C again to quit without them)"
        );
    };
    // Only the first render of a process can install it (`ctrlc` allows one handler); a
    // host that renders again keeps the first flag's handler, which this render then misses.
    if ctrlc::set_handler(handler).is_err() {
        return Arc::new(AtomicBool::new(false));
    }
    flag
}

/// `render`'s flags from `argv` (without the program and command names), parsed as the command
/// line parses them; an error is clap's message, its first line without `error: `.
pub fn parse_args(argv: &[String]) -> Result<RenderArgs, String> {
    use clap::{Args, FromArgMatches};
    let cmd = RenderArgs::augment_args(clap::Command::new("render").no_binary_name(true));
    cmd.try_get_matches_from(argv)
        .and_then(|m| RenderArgs::from_arg_matches(&m))
        .map_err(|e| {
            let text = e.render().to_string();
            let line = text.lines().next().unwrap_or_default();
            line.strip_prefix("error: ").unwrap_or(line).to_string()
        })
}

/// A render ready to run: the strategy built for the scene, the settings and what chose them.
pub struct Prepared {
    pub strategy: Box<dyn DirectLighting>,
    pub settings: RenderSettings,
    choices: Choices,
    resolved: serde_json::Value,
}

/// The strategy and the settings the flags ask for on `scene` (loaded from `args.scene` with
/// `args.camera`), or the error the command line gives.
pub fn prepare(args: &RenderArgs, scene: &Scene) -> anyhow::Result<Prepared> {
    let opts = args.strategy.options()?;
    let emission_rays = args.strategy.emission_rays()?;
    let resolved = args.strategy.resolved()?;
    let choices = choose(args, scene, opts.reproduce);
    let strategy = samplers::create(&args.strategy.strategy, scene, &opts)?;
    let settings = settings(
        args,
        scene,
        &choices,
        emission_rays,
        strategy.aux_channels().len(),
    )?;
    Ok(Prepared {
        strategy,
        settings,
        choices,
        resolved,
    })
}

impl Prepared {
    /// The render's JSON record, as `render` writes it when it writes no file besides the EXR;
    /// `scene_hash` is `scene`'s [`Scene::content_hash`], which a caller rendering one scene
    /// many times computes once.
    pub fn metadata(
        &self,
        args: &RenderArgs,
        (scene, scene_hash): (&Scene, &str),
        result: &RenderResult,
    ) -> serde_json::Value {
        let written = report::Written::nothing();
        let p = self;
        report::metadata(
            args,
            (scene, scene_hash),
            p.strategy.as_ref(),
            &p.settings,
            &p.choices,
            result,
            p.resolved.clone(),
            &written,
        )
    }
}

/// `manylights render`: the exit code is 0, or 130 for a render that Ctrl-C ended early (its
/// samples written all the same).
pub fn run(args: RenderArgs) -> anyhow::Result<std::process::ExitCode> {
    check_args(&args)?;
    check_outputs(&args)?;
    if !args.quiet {
        for w in ignored_flags(&args) {
            eprintln!("warning: {w}");
        }
    }
    let mut scene = scene_formats::load_scene(&args.scene, args.camera.as_deref())?;
    scene.light_points = args.strategy.light_points;
    if !args.quiet {
        for w in &scene.stats.warnings {
            eprintln!("warning: {w}");
        }
    }
    let prepared = prepare(&args, &scene)?;
    if scene.lights.is_empty() && scene.distant_lights.is_empty() {
        eprintln!("warning: the scene has no lights; the image will be black");
    }
    let s = &scene.stats;
    let delta = s.point_lights + s.spot_lights + s.distant_lights;
    if args.strategy.strategy == "bsdf" && delta > 0 {
        eprintln!(
            "warning: BSDF sampling cannot reach the scene's {delta} point, spot and distant \
             lights: they add nothing to this image (a light-sampling strategy sees them)"
        );
    }
    let Prepared {
        strategy,
        settings,
        choices,
        resolved,
    } = prepared;
    outputs::check_planned(&args, &strategy.aux_channels())?;
    let result = render_with_progress(&args, &scene, strategy.as_ref(), &settings)?;
    let mut files = FileSet::default();
    let written = report::write_images(&args, strategy.as_ref(), &settings, &result, &mut files)?;
    let meta = report::metadata(
        &args,
        (&scene, &scene.content_hash()),
        strategy.as_ref(),
        &settings,
        &choices,
        &result,
        resolved,
        &written,
    );
    report::stage(
        &mut files,
        &outputs::json_path(&args.out),
        json_encoder(&meta),
    )?;
    files.commit().map_err(anyhow::Error::msg)?;
    if args.stats || !args.quiet {
        report::print_summary(&result);
    }
    if args.stats {
        report::print_stats(&result, &strategy.counters());
    }
    Ok(match result.interrupted {
        true => std::process::ExitCode::from(130),
        false => std::process::ExitCode::SUCCESS,
    })
}
