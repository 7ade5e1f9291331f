//! Deterministic fuzzing of the scene inputs. Case `k` of a run with seed `s` mutates one of
//! the valid [`corpus`] inputs with a generator seeded by (s, k) alone, writes it into the
//! run's directory, loads it with `scene_formats::load_scene` and, when it loads, renders it at
//! 8×6 pixels and 1 spp with one of the registered strategies (in turn). A case passes when it
//! ends in a scene or an error, and fails on:
//!
//! * a panic, even one the loader catches (a panic hook counts them),
//! * an error message of more than one line (the CLI prints it after `error: `),
//! * a non-finite pixel (a silent wrong image),
//! * a single allocation larger than [`ALLOCATION_LIMIT`] (only where the binary installs
//!   [`CountingAllocator`] as its global allocator),
//! * taking longer than [`CASE_TIME_LIMIT`] (a watchdog aborts the process and names the case).
//!
//! The test `tests/fuzz.rs` runs a few thousand cases; `cargo xtask fuzz --minutes N` runs more.
pub mod corpus;
pub mod mutate;

use corpus::{Kind, PLACED_GLB, Seed};
use rand::SeedableRng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, Once};
use std::time::{Duration, Instant};

/// The largest single allocation a case may make: far above what these small files can
/// describe (an 8×6 render, scenes of a few triangles or a few thousand lights).
pub const ALLOCATION_LIMIT: usize = 256 << 20;

/// A case taking longer than this is a hang.
pub const CASE_TIME_LIMIT: Duration = Duration::from_secs(30);

static LARGEST_ALLOCATION: AtomicUsize = AtomicUsize::new(0);
static TRACKING: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, recording the largest single request since [`reset_largest`]. It
/// refuses requests above 16 GiB outright (the process then aborts with the allocation error,
/// and the case file left in the run directory is the one that did it).
pub struct CountingAllocator;

const REFUSE: usize = 16 << 30;

// SAFETY: every call is forwarded to `System` unchanged, except oversized requests, which get
// the null pointer that `GlobalAlloc` allows as a failure.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if note(layout.size()) {
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded as received.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if note(layout.size()) {
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded as received.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded as received.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if note(new_size) {
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded as received.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Records a request; true when it must be refused.
fn note(size: usize) -> bool {
    TRACKING.store(1, Ordering::Relaxed);
    LARGEST_ALLOCATION.fetch_max(size, Ordering::Relaxed);
    size > REFUSE
}

fn reset_largest() {
    LARGEST_ALLOCATION.store(0, Ordering::Relaxed);
}

/// Whether the running binary counts allocations (it installed [`CountingAllocator`]).
pub fn allocations_tracked() -> bool {
    TRACKING.load(Ordering::Relaxed) == 1
}

static PANICS: AtomicUsize = AtomicUsize::new(0);
/// Set while a case runs: panics then are counted, not reported by the previous hook.
static IN_CASE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
static PANIC_MESSAGES: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Replaces the panic hook by one that counts panics and keeps their messages (a panic the
/// loader catches is still a bug: the loader's own checks should have seen the bad input).
fn install_panic_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !IN_CASE.load(Ordering::SeqCst) {
                return previous(info);
            }
            PANICS.fetch_add(1, Ordering::SeqCst);
            let loc = info
                .location()
                .map(|l| format!("{}:{}", l.file(), l.line()))
                .unwrap_or_default();
            let msg = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_default();
            if let Ok(mut m) = PANIC_MESSAGES.lock() {
                m.push(format!("{msg} at {loc}"));
            }
        }));
    });
}

/// How a passing case ended.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Outcome {
    /// Loaded and rendered.
    Rendered,
    /// Loaded; the strategy or the render refused it with an error.
    RenderRefused,
    /// The loader refused it with an error.
    Refused,
}

/// A failed case: what went wrong and how to reproduce it.
#[derive(Clone, Debug)]
pub struct Failure {
    pub case: u64,
    pub seed_name: String,
    pub ops: Vec<String>,
    pub problem: String,
    /// Where the input was saved.
    pub input: PathBuf,
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "case {} ({} mutated by {}): {} — input kept at {}",
            self.case,
            self.seed_name,
            self.ops.join("; "),
            self.problem,
            self.input.display()
        )
    }
}

/// What a run did.
#[derive(Debug, Default)]
pub struct Report {
    pub cases: u64,
    pub outcomes: std::collections::BTreeMap<String, u64>,
    pub failures: Vec<Failure>,
    pub largest_allocation: usize,
    pub seconds: f64,
    pub notices: Vec<String>,
}

/// A fuzzing run: the seeds, its directory and its generator seed.
pub struct Fuzzer {
    seeds: Vec<Seed>,
    dir: PathBuf,
    run_seed: u64,
    notices: Vec<String>,
}

impl Fuzzer {
    /// Prepares `dir` (created, with the glTF file the compositions place). `shared_scenes`:
    /// the `../shared/scenes` directory, whose small files join the seeds when present.
    pub fn new(dir: &Path, run_seed: u64, shared_scenes: Option<&Path>) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let mut notices = Vec::new();
        let seeds = corpus::seeds(shared_scenes, &mut notices);
        std::fs::write(
            dir.join(PLACED_GLB),
            corpus::encode(&corpus::studio(), Kind::Glb),
        )?;
        Ok(Fuzzer {
            seeds,
            dir: dir.to_path_buf(),
            run_seed,
            notices,
        })
    }

    pub fn seeds(&self) -> &[Seed] {
        &self.seeds
    }

    /// Runs cases `first..` until `count` cases ran or `deadline` passed.
    pub fn run(&self, first: u64, count: u64, deadline: Option<Instant>) -> Report {
        install_panic_hook();
        let watchdog = Watchdog::start(self.dir.clone());
        let start = Instant::now();
        let mut report = Report {
            notices: self.notices.clone(),
            ..Default::default()
        };
        for case in first..first.saturating_add(count) {
            if deadline.is_some_and(|d| Instant::now() >= d) {
                break;
            }
            watchdog.begin(case);
            match self.run_case(case) {
                Ok(outcome) => *report.outcomes.entry(format!("{outcome:?}")).or_default() += 1,
                Err(f) => report.failures.push(f),
            }
            report.largest_allocation = report
                .largest_allocation
                .max(LARGEST_ALLOCATION.load(Ordering::Relaxed));
            report.cases += 1;
        }
        watchdog.stop();
        report.seconds = start.elapsed().as_secs_f64();
        report
    }

    /// Runs one case; `Err` describes a failure (the input is then kept beside the run's files).
    pub fn run_case(&self, case: u64) -> Result<Outcome, Failure> {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(
            self.run_seed ^ case.wrapping_mul(0x9e37_79b9_7f4a_7c15),
        );
        let seed = &self.seeds[(case % self.seeds.len() as u64) as usize];
        let mutant = mutate::mutate(seed, &mut rng);
        let path = self.dir.join(format!("case.{}", seed.kind().extension()));
        let fail = |problem: String| {
            let kept = self
                .dir
                .join(format!("failure-{case}.{}", seed.kind().extension()));
            let _ = std::fs::write(&kept, &mutant.bytes);
            Failure {
                case,
                seed_name: seed.name().to_string(),
                ops: mutant.ops.clone(),
                problem,
                input: kept,
            }
        };
        std::fs::write(&path, &mutant.bytes).map_err(|e| fail(format!("cannot write: {e}")))?;
        let panics_before = PANICS.load(Ordering::SeqCst);
        reset_largest();
        IN_CASE.store(true, Ordering::SeqCst);
        let result = std::panic::catch_unwind(|| load_and_render(&path, case));
        IN_CASE.store(false, Ordering::SeqCst);
        let largest = LARGEST_ALLOCATION.load(Ordering::Relaxed);
        if PANICS.load(Ordering::SeqCst) != panics_before {
            let msgs = PANIC_MESSAGES
                .lock()
                .map(|m| m.last().cloned().unwrap_or_default())
                .unwrap_or_default();
            return Err(fail(format!("panicked: {msgs}")));
        }
        if largest > ALLOCATION_LIMIT {
            return Err(fail(format!(
                "allocated {largest} bytes at once from a {}-byte file",
                mutant.bytes.len()
            )));
        }
        match result {
            Ok(r) => r.map_err(fail),
            Err(_) => Err(fail("panicked".into())),
        }
    }
}

/// Loads the case; if it loads, renders it small. `Err` is a failure, not a refusal.
fn load_and_render(path: &Path, case: u64) -> Result<Outcome, String> {
    let one_line = |e: String| {
        if e.contains('\n') || e.trim().is_empty() {
            Err(format!("error message is not one line: {e:?}"))
        } else {
            Ok(())
        }
    };
    let scene = match scene_formats::load_scene(&path.display().to_string(), None) {
        Ok(s) => s,
        Err(e) => {
            one_line(e.to_string())?;
            return Ok(Outcome::Refused);
        }
    };
    let mut camera = match scene.camera(None) {
        Ok(c) => c,
        Err(e) => {
            one_line(e.to_string())?;
            return Ok(Outcome::RenderRefused);
        }
    };
    // The size the file asks for is checked as the CLI would check it (no allocation).
    if let Err(e) = render_core::render::check_memory(camera.width, camera.height, 4) {
        one_line(e)?;
    }
    let strategies = samplers::strategies();
    let name = strategies[(case % strategies.len() as u64) as usize].name;
    let strategy = match samplers::create(name, &scene, &samplers::StrategyOptions::default()) {
        Ok(s) => s,
        Err(e) => {
            one_line(e.to_string())?;
            return Ok(Outcome::RenderRefused);
        }
    };
    camera.width = 8;
    camera.height = 6;
    let settings = render_core::render::RenderSettings {
        width: 8,
        height: 6,
        spp: Some(1),
        seed: case,
        time_budget: None,
        threads: Some(1),
        camera,
        sampler: Default::default(),
        filter: Default::default(),
        reconstruction: Default::default(),
        emission_rays: Default::default(),
        engine: Default::default(),
    };
    match render_core::render::render(&scene, strategy.as_ref(), &settings, &|_, _| {}) {
        Ok(r) => {
            if let Some(p) = r.pixels.iter().position(|p| !p.is_finite()) {
                return Err(format!(
                    "{name}: pixel {p} is {:?} (a silent wrong image)",
                    r.pixels[p]
                ));
            }
            Ok(Outcome::Rendered)
        }
        Err(e) => {
            one_line(e)?;
            Ok(Outcome::RenderRefused)
        }
    }
}

/// Aborts the process when a case runs longer than [`CASE_TIME_LIMIT`], naming it.
struct Watchdog {
    /// The case running, [`Watchdog::IDLE`] between cases, [`Watchdog::STOP`] to end.
    case: std::sync::Arc<AtomicU64>,
    /// When it started, in ms since `origin`.
    started_ms: std::sync::Arc<AtomicU64>,
    origin: Instant,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Watchdog {
    const IDLE: u64 = u64::MAX;
    const STOP: u64 = u64::MAX - 1;

    fn start(dir: PathBuf) -> Self {
        let case = std::sync::Arc::new(AtomicU64::new(Self::IDLE));
        let started_ms = std::sync::Arc::new(AtomicU64::new(0));
        let origin = Instant::now();
        let (c, s) = (case.clone(), started_ms.clone());
        let thread = std::thread::spawn(move || {
            loop {
                std::thread::sleep(Duration::from_millis(100));
                let running = c.load(Ordering::SeqCst);
                if running == Self::STOP {
                    return;
                }
                let ran =
                    (origin.elapsed().as_millis() as u64).saturating_sub(s.load(Ordering::SeqCst));
                if running != Self::IDLE && ran > CASE_TIME_LIMIT.as_millis() as u64 {
                    eprintln!(
                        "scene-fuzz: case {running} ran longer than {CASE_TIME_LIMIT:?}: a hang \
                         (its input is the case.* file in {})",
                        dir.display()
                    );
                    std::process::abort();
                }
            }
        });
        Watchdog {
            case,
            started_ms,
            origin,
            thread: Some(thread),
        }
    }

    fn begin(&self, case: u64) {
        self.started_ms
            .store(self.origin.elapsed().as_millis() as u64, Ordering::SeqCst);
        self.case.store(case, Ordering::SeqCst);
    }

    fn stop(mut self) {
        self.case.store(Self::STOP, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
