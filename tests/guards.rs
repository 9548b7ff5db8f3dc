//! Guards on bad input and runaway runs (issue 22): `check` rejects what
//! `run` rejects before its first step; a scene too large for the machine
//! is refused before allocating; a run whose Δt collapses or projects an
//! absurd number of steps stops naming the cause; numerical failures name
//! materials by scene name and `materials[i]`; after a failure the last
//! snapshot is a good state and no snapshot time repeats; OS errors name
//! their path once.

use std::path::Path;
use std::process::Command;

use mpmice::driver::{check_scene, run_model, run_scene, RunOptions};
use mpmice::error::Error;
use mpmice::scene::Scene;

fn case_text(name: &str) -> String {
    std::fs::read_to_string(format!("{}/cases/{name}", env!("CARGO_MANIFEST_DIR"))).expect("case")
}

fn case(name: &str) -> Scene {
    mpmice::scene::parse(&case_text(name)).expect("case parses")
}

fn opts(dir: &Path) -> RunOptions {
    RunOptions::quiet(dir, 1)
}

/// `text` with `from` replaced by `to` (which must occur once).
fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "edit anchor `{from}`");
    text.replacen(from, to, 1)
}

/// The CLI's verb on scene text: (success, stderr).
fn cli(verb: &str, text: &str, dir: &Path, extra: &[&str]) -> (bool, String) {
    let path = dir.join(format!("{verb}.toml"));
    std::fs::write(&path, text).expect("write");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mpmice"));
    cmd.arg(verb).arg(&path).args(extra);
    if verb == "run" {
        cmd.arg("--out").arg(dir.join("out")).arg("--quiet");
    }
    let out = cmd.output().expect("spawn");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Scenes that parse but that `run` rejects before its first step (while
/// building them): `check` rejects each of them too, with the same key
/// and message, through the library and through both CLI verbs.
#[test]
fn check_rejects_what_run_rejects_before_the_first_step() {
    let disks = case_text("two_disks.toml");
    let sod = case_text("sod.toml");
    let cases: Vec<(String, &str, &str)> = vec![
        (
            // An object smaller than a particle spacing: no particle.
            edit(
                &disks,
                "center = [0.25, 0.25], radius = 0.2",
                "center = [0.25, 0.25], radius = 0.001",
            ),
            "objects[0].geometry",
            "no particle",
        ),
        (
            // A fluid whose regions leave cells uncovered.
            edit(
                &sod,
                "pressure = 0.1\n",
                "geometry = { type = \"box\", lower = [0.0], upper = [0.2] }\npressure = 0.1\n",
            ),
            "regions",
            "lies in no region",
        ),
        (
            // E = 1e308: Δt ~ 1e-155 s; the run would never end.
            edit(&disks, "youngs_modulus = 1000.0", "youngs_modulus = 1e308"),
            "",
            "time.max_projected_steps",
        ),
    ];
    let tmp = tempfile::tempdir().expect("tmp");
    for (k, (text, key, word)) in cases.iter().enumerate() {
        let s = mpmice::scene::parse(text).unwrap_or_else(|e| panic!("case {k} parses: {e}"));
        let checked = check_scene(&s, &opts(tmp.path()))
            .err()
            .unwrap_or_else(|| panic!("case {k}: check accepts"))
            .to_string();
        let dir = tmp.path().join(format!("run{k}"));
        let ran = run_scene(&s, &opts(&dir))
            .err()
            .unwrap_or_else(|| panic!("case {k}: run accepts"))
            .to_string();
        println!("case {k}: {checked}");
        assert_eq!(checked, ran, "case {k}: check and run differ");
        assert!(checked.contains(key) && checked.contains(word), "{checked}");
        // Nothing was stepped: the run wrote no output folder.
        assert!(!dir.join("history.csv").exists(), "case {k}");
        for verb in ["check", "run"] {
            let (ok, err) = cli(verb, text, tmp.path(), &[]);
            assert!(!ok, "{verb} case {k} must fail");
            assert!(err.contains(key) && err.contains(word), "{verb}: {err}");
            assert!(!err.contains("panicked"), "{verb}: {err}");
        }
    }
}

/// Every case of `cases/` passes `check` (the validation `run` does before
/// its first step) within the machine's memory.
#[test]
fn every_case_passes_check() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/cases");
    let mut n = 0;
    for e in std::fs::read_dir(dir).expect("cases") {
        let p = e.expect("entry").path();
        if p.extension().is_some_and(|x| x == "toml") {
            let s = mpmice::scene::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            let r = check_scene(&s, &RunOptions::default())
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert!(r.preflight.dt > 0.0 && r.memory.total() > 0.0 || s.grid.dim == 0);
            n += 1;
        }
    }
    assert!(n >= 20, "{n} cases");
}

/// A grid of 10¹² cells is refused before anything is allocated, naming
/// `grid.cells` and the estimate; a small memory limit refuses a small
/// scene; the override goes on.
#[test]
fn a_scene_larger_than_the_memory_is_refused_before_allocating() {
    let tmp = tempfile::tempdir().expect("tmp");
    let huge = edit(
        &case_text("two_disks.toml"),
        "cells = [64, 64]",
        "cells = [1000000, 1000000]",
    );
    let s = mpmice::scene::parse(&huge).expect("valid");
    let start = std::time::Instant::now();
    let e = check_scene(&s, &opts(tmp.path())).expect_err("refused");
    let msg = e.to_string();
    println!("{msg}");
    let Error::Scene(se) = &e else {
        panic!("{msg}")
    };
    assert_eq!(se.path, "grid.cells", "{msg}");
    assert!(
        msg.contains("needs about") && msg.contains("available"),
        "{msg}"
    );
    assert!(msg.contains("--ignore-memory-limit"), "{msg}");
    // The estimate: 1e12 cells, ≥ 1e12 × 8 bytes × node fields.
    assert!(mpmice::driver::MemoryEstimate::of(&s).grid_bytes > 1e13);
    let e = run_scene(&s, &opts(tmp.path())).expect_err("run refuses too");
    assert!(e.to_string().contains("grid.cells"));
    assert!(
        start.elapsed().as_secs_f64() < 5.0,
        "refused before allocating"
    );
    for verb in ["check", "run"] {
        let (ok, err) = cli(verb, &huge, tmp.path(), &[]);
        assert!(
            !ok && err.contains("grid.cells") && err.contains("needs about"),
            "{err}"
        );
    }
    // A 1 MiB limit refuses the 64 × 64 disks (about 4 MiB), naming the
    // grid or the object that drives the estimate; the override runs check.
    let s = case("two_disks.toml");
    let est = mpmice::driver::MemoryEstimate::of(&s);
    println!("two disks: {}", est.describe());
    assert!(est.total() > 1.0 * 1024.0 * 1024.0 && est.total() < 64.0 * 1024.0 * 1024.0);
    // 2 disks of radius 0.2 on 64² cells, 2 × 2 per cell: ≈ 2 × 1030
    // particles; the bounding-box estimate is an upper bound of it.
    assert!(est.particles >= 2000.0 && est.particles <= 2.0 * 28.0 * 28.0 * 4.0);
    let small = RunOptions {
        memory_limit: Some(1 << 20),
        ..opts(tmp.path())
    };
    let e = check_scene(&s, &small).expect_err("1 MiB is too little");
    assert!(
        matches!(&e, Error::Scene(se) if se.path == "grid.cells" || se.path.starts_with("objects[")),
        "{e}"
    );
    let report = check_scene(
        &s,
        &RunOptions {
            ignore_memory_limit: true,
            ..small
        },
    )
    .expect("override");
    // π 0.2² × 128² ≈ 2059 particles a disk.
    let n = report.counts.particles as f64;
    assert!(
        n <= est.particles && n > 0.6 * est.particles,
        "{n} vs {}",
        est.particles
    );
}

/// A membrane mesh of 16384² elements is refused before it is built
/// (parsing no longer builds meshes above a million elements), naming the
/// mesh key.
#[test]
fn a_membrane_mesh_larger_than_the_memory_is_refused_before_building() {
    let tmp = tempfile::tempdir().expect("tmp");
    let text = edit(
        &case_text("lian_membrane_vibration.toml"),
        "cells = [32, 32]",
        "cells = [16384, 16384]",
    );
    let start = std::time::Instant::now();
    let s = mpmice::scene::parse(&text).expect("valid");
    let e = check_scene(&s, &opts(tmp.path())).expect_err("refused");
    println!("{e}");
    assert!(
        matches!(&e, Error::Scene(se) if se.path == "membrane_elements[0].mesh"),
        "{e}"
    );
    assert!(e.to_string().contains("2.684e8 membrane elements"), "{e}");
    assert!(
        start.elapsed().as_secs_f64() < 5.0,
        "refused before building"
    );
}

/// E = 1e308 makes Δt ≈ 1e-155 s: check and run stop before the first
/// step naming the particle, the material by scene name and index, and the
/// key that bounds the projection.
#[test]
fn an_absurd_projected_step_count_names_the_particle_and_material() {
    let tmp = tempfile::tempdir().expect("tmp");
    let mut s = case("two_disks.toml");
    s.materials[0].youngs_modulus = Some(1e308);
    let e = check_scene(&s, &opts(tmp.path())).expect_err("refused");
    let msg = e.to_string();
    println!("{msg}");
    assert!(matches!(e, Error::Progress { step: 0, .. }), "{msg}");
    for part in [
        "time.max_projected_steps",
        "particle ",
        "material `elastic` (materials[0])",
        "signal speed",
    ] {
        assert!(msg.contains(part), "`{part}` missing: {msg}");
    }
    // Bounded by time.max_steps, the same scene is accepted.
    s.time.max_steps = Some(10);
    check_scene(&s, &opts(tmp.path())).expect("bounded by max_steps");
}

/// The same for the models besides the explicit solid that name what sets
/// their Δt: a multiphase scene names the particle and its phase, a
/// membrane of elements the element and the membrane.
#[test]
fn an_absurd_projected_step_count_names_the_site_in_every_explicit_model() {
    let tmp = tempfile::tempdir().expect("tmp");
    let mut phases = case("zhang_block.toml");
    phases.materials[0].youngs_modulus = Some(1e308);
    let mut membrane = case("lian_membrane_vibration.toml");
    membrane.membrane_elements[0].young = 1e300;
    for (s, parts) in [
        (
            phases,
            &["particle ", " of phase 0", "material `disk` (materials[0])"][..],
        ),
        (membrane, &["element ", "`sheet`"][..]),
    ] {
        let e = check_scene(&s, &opts(tmp.path())).expect_err("refused");
        let msg = e.to_string();
        println!("{msg}");
        assert!(matches!(e, Error::Progress { step: 0, .. }), "{msg}");
        for part in parts
            .iter()
            .chain(&["time.max_projected_steps", "signal speed"])
        {
            assert!(msg.contains(part), "`{part}` missing: {msg}");
        }
    }
}

/// An explicit solid whose step can shrink its Δt geometrically (a
/// collapsing run), or fail after half-updating its particles (as a
/// blow-up would).
struct Faulty {
    inner: mpmice::driver::models::ExplicitSolid<2>,
    /// Each step's Δt cap is this factor times the previous step's.
    shrink: Option<f64>,
    last_dt: f64,
    /// The step that fails after moving every particle to NaN.
    fail_at: Option<u64>,
}

impl mpmice::driver::Model for Faulty {
    fn kind(&self) -> String {
        self.inner.kind()
    }
    fn time(&self) -> f64 {
        self.inner.time()
    }
    fn steps(&self) -> u64 {
        self.inner.steps()
    }
    fn stable_dt(&self) -> f64 {
        self.inner.stable_dt()
    }
    fn step(
        &mut self,
        mut dt: mpmice::driver::DtRequest,
    ) -> Result<mpmice::driver::StepStats, Error> {
        if let Some(f) = self.shrink {
            if self.last_dt > 0.0 {
                dt.value = dt.value.min(f * self.last_dt);
            }
        }
        let st = self.inner.step(dt)?;
        self.last_dt = st.dt;
        if Some(self.inner.steps()) == self.fail_at {
            for x in &mut self.inner.run.particles.x {
                x[0] = f64::NAN;
            }
            return Err(Error::Numerical {
                site: mpmice::error::FailureSite {
                    step: self.inner.steps(),
                    time: self.inner.time(),
                    particle: Some(3),
                    cell: None,
                },
                what: "particle left the grid".into(),
            });
        }
        Ok(st)
    }
    fn annotate(&self, e: Error) -> Error {
        self.inner.annotate(e)
    }
    fn field_sets(&self) -> Vec<mpmice::driver::model::FieldSet<'_>> {
        self.inner.field_sets()
    }
    fn history_columns(&self) -> Vec<(&'static str, &'static str)> {
        self.inner.history_columns()
    }
    fn history_row(&self, row: &mut Vec<f64>) {
        self.inner.history_row(row)
    }
    fn conserved(&self) -> mpmice::driver::model::Conserved {
        self.inner.conserved()
    }
    fn watchdog(&self) -> Option<mpmice::driver::model::Violation> {
        self.inner.watchdog()
    }
    fn save(&self, ck: &mut mpmice::output::checkpoint::Checkpoint) {
        self.inner.save(ck)
    }
    fn load(
        &mut self,
        ck: &mut mpmice::output::checkpoint::Checkpoint,
    ) -> Result<(), mpmice::output::checkpoint::CheckpointError> {
        self.inner.load(ck)
    }
    fn counts(&self) -> mpmice::driver::model::Counts {
        self.inner.counts()
    }
    fn describe(&self) -> mpmice::driver::model::Description {
        self.inner.describe()
    }
    fn dt_limiter(&self) -> Option<mpmice::driver::DtLimiter> {
        self.inner.dt_limiter()
    }
}

fn faulty(s: &Scene, shrink: Option<f64>, fail_at: Option<u64>) -> Faulty {
    Faulty {
        inner: mpmice::driver::models::ExplicitSolid {
            run: mpmice::scene::build_solid_run::<2>(s).expect("build"),
        },
        shrink,
        last_dt: 0.0,
        fail_at,
    }
}

fn small_disks() -> Scene {
    let mut s = case("two_disks.toml");
    s.grid.cells = vec![16, 16];
    s.output.interval = Some(0.05);
    s
}

/// The step a progress-guard stop happened at and the step of its
/// checkpoint (panics on any other error).
fn progress_stop(e: &Error) -> (u64, u64) {
    let Error::Stopped {
        cause, step: saved, ..
    } = e
    else {
        panic!("not a stop with a checkpoint: {e}")
    };
    let Error::Progress { step, .. } = **cause else {
        panic!("not the progress guard: {e}")
    };
    (step, *saved)
}

/// A Δt halving every step falls below 1e-6 of the largest after 20
/// steps: the run stops there naming the key, Δt and what sets the stable
/// step, with a checkpoint of that (whole) step.
#[test]
fn a_collapsing_time_step_stops_the_run_naming_the_cause() {
    let tmp = tempfile::tempdir().expect("tmp");
    let s = small_disks();
    let mut m = faulty(&s, Some(0.5), None);
    let e = run_model(&mut m, &s, &opts(tmp.path()), 1).expect_err("stops");
    let msg = e.to_string();
    println!("{msg}");
    let (step, saved) = progress_stop(&e);
    // Δt_k = 2^-k Δt_0 < 1e-6 Δt_0 first at k = 20, the 21st step.
    assert_eq!(step, 21, "{msg}");
    assert_eq!(saved, 21, "{msg}");
    for part in [
        "time.min_dt_fraction",
        "particle ",
        "material `elastic` (materials[0])",
    ] {
        assert!(msg.contains(part), "`{part}` missing: {msg}");
    }
    // One warning, at the first 100-fold drop: Δt_k < Δt_0/100 first at
    // k = 7, the 8th step.
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(tmp.path().join("summary.json")).expect("summary"),
    )
    .expect("json");
    let warnings = summary["warnings"].as_array().expect("warnings");
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let w = warnings[0].as_str().unwrap();
    assert!(w.contains("100-fold") && w.contains("at step 8,"), "{w}");
    // The default fraction is a scene key; a smaller one lets it go on.
    let mut s2 = small_disks();
    s2.time.min_dt_fraction = 1e-9;
    let mut m = faulty(&s2, Some(0.5), None);
    let e = run_model(&mut m, &s2, &opts(&tmp.path().join("b")), 1).expect_err("stops");
    assert!(
        matches!(&e, Error::Stopped { cause, .. } if matches!(**cause, Error::Progress { step: 31, .. })),
        "{e}"
    );
}

/// The implicit solid's Δt is its Newton step control's, not a wave limit:
/// when it collapses, the guard names the failed solve that last cut it
/// (particle, material, the Δt that failed and the solver's reason), and
/// the checkpoint holds the whole step the run stopped after, not an
/// earlier state. The pressurised cylinder with 3 Newton iterations per
/// attempt cuts Δt from 0.195 to 7.6e-3 by step 5.
#[test]
fn a_collapsing_implicit_time_step_names_the_failed_solve() {
    let tmp = tempfile::tempdir().expect("tmp");
    let mut s = case("pressurized_cylinder_impm.toml");
    s.implicit.max_newton_iterations = 3;
    s.time.min_dt_fraction = 0.3;
    let (step, saved, msg) = progress_stop_naming(
        &s,
        tmp.path(),
        &[
            "time.min_dt_fraction",
            "particle ",
            "material `steel` (materials[0])",
            "the last Δt cut",
            "Newton did not converge in 3 iterations",
        ],
    );
    assert!(step > 1, "{msg}");
    assert_eq!(
        saved, step,
        "the checkpoint is the step the guard stopped after: {msg}"
    );
    let times = pvd_times(&tmp.path().join("particles.pvd"));
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
}

/// A coupled run whose Δt is not wave-limited (implicit pressure and a
/// quasistatic implicit steel) names the cut that collapsed it, not a wave
/// speed: the pressurised cylinder without momentum exchange has its
/// pressure stage halved 100-fold within two steps, and the guard blamed
/// the steel's sound speed at particle 80 (a limit of 1.1e-5 s that no
/// step of this mode obeys).
#[test]
fn a_collapsing_coupled_implicit_time_step_names_the_cut() {
    let tmp = tempfile::tempdir().expect("tmp");
    let mut s = case("pressurized_cylinder_implicit.toml");
    s.coupling.momentum_exchange = 0.0;
    s.time.min_dt_fraction = 0.3;
    let (step, _, msg) = progress_stop_naming(
        &s,
        tmp.path(),
        &[
            "time.min_dt_fraction",
            "the last Δt cut",
            "the pressure stage",
        ],
    );
    assert!(step >= 1, "{msg}");
    assert!(!msg.contains("signal speed"), "{msg}");
}

/// Runs `s` into `dir`, which the progress guard must stop with a message
/// holding every one of `parts`: the guard's step, the checkpoint's step
/// and the message.
fn progress_stop_naming(s: &Scene, dir: &Path, parts: &[&str]) -> (u64, u64, String) {
    let e = run_scene(s, &opts(dir)).expect_err("stops");
    let msg = e.to_string();
    println!("{msg}");
    let (step, saved) = progress_stop(&e);
    for part in parts {
        assert!(msg.contains(part), "`{part}` missing: {msg}");
    }
    (step, saved, msg)
}

/// The times of a `.pvd` series.
fn pvd_times(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).expect("pvd");
    text.lines()
        .filter_map(|l| l.split("timestep=\"").nth(1))
        .map(|r| r.split('"').next().unwrap().parse::<f64>().expect("time"))
        .collect()
}

/// A step that fails after moving every particle to NaN: the run stops,
/// the last snapshot (VTK and CSV) is a good state — not the half-updated
/// one — and no time appears twice in the `.pvd`.
#[test]
fn after_a_failure_the_last_snapshot_is_the_last_good_state() {
    for (watchdog, fail_at) in [(10u64, 23u64), (10, 30), (1, 7), (0, 12)] {
        let tmp = tempfile::tempdir().expect("tmp");
        let mut s = small_disks();
        s.time.watchdog_interval = watchdog;
        let mut m = faulty(&s, None, Some(fail_at));
        let e = run_model(&mut m, &s, &opts(tmp.path()), 1).expect_err("fails");
        println!("watchdog {watchdog}, failing step {fail_at}: {e}");
        assert!(e.to_string().contains("particle left the grid"));
        let times = pvd_times(&tmp.path().join("particles.pvd"));
        assert!(
            times.windows(2).all(|w| w[1] > w[0]),
            "snapshot times repeat or go back: {times:?}"
        );
        // The last CSV snapshot holds finite positions only.
        let last = times.len() - 1;
        let csv = std::fs::read_to_string(tmp.path().join(format!("particles_{last:04}.csv")))
            .expect("csv");
        assert!(
            !csv.to_lowercase().contains("nan"),
            "NaN in the last snapshot"
        );
        // With a last good state, the run ends there (summary and pvd).
        if watchdog > 0 {
            let Error::Stopped { time, step, .. } = &e else {
                panic!("{e}")
            };
            assert!(*step < fail_at);
            assert!(times[last] >= *time, "{times:?} vs {time}");
        }
    }
}

/// A coupled scene: a steel box in air. ICE numbers the fluid `air` 0,
/// while `materials[0]` is the steel.
const COUPLED: &str = r#"
[grid]
dim = 2
lower = [0.0, 0.0]
upper = [1.0, 1.0]
cells = [10, 10]
boundary = { x_lower = "fixed", y_lower = "symmetry" }

[time]
end = 0.1
cfl = 0.5

[[materials]]
name = "steel"
type = "solid"
model = "linear_elastic"
density = 7800.0
youngs_modulus = 200e9
poisson_ratio = 0.3

[[objects]]
material = "steel"
geometry = { type = "box", lower = [0.2, 0.2], upper = [0.8, 0.8] }
velocity = [1.0, 0.0]

[[materials]]
name = "air"
type = "fluid"
eos = "ideal_gas"
gamma = 1.4
cv = 717.5

[[regions]]
pressure = 101325.0
states = [{ material = "air", volume_fraction = 1.0, density = 1.1768 }]
"#;

/// Numerical failures name materials by scene name and `materials[i]`: in
/// the coupled scene a scalding air region makes Δt absurd, and the
/// message names the cell and `air` (materials[1]), never "material 0".
#[test]
fn failures_name_materials_by_scene_name_and_index() {
    let tmp = tempfile::tempdir().expect("tmp");
    let hot = edit(COUPLED, "density = 1.1768", "temperature = 1e290");
    let s = mpmice::scene::parse(&hot).expect("coupled scene");
    let e = check_scene(&s, &opts(tmp.path())).expect_err("absurd Δt");
    let msg = e.to_string();
    println!("{msg}");
    assert!(
        msg.contains("cell [") && msg.contains("`air` (materials[1])"),
        "{msg}"
    );
    assert!(!msg.contains("material 0"), "{msg}");
    // The same labels in any message that names a material.
    assert_eq!(
        s.label_materials("NaN at particle 3 of material `steel`, material `air`"),
        "NaN at particle 3 of material `steel` (materials[0]), material `air` (materials[1])"
    );
    assert_eq!(
        s.label_materials("material `air` (materials[1])"),
        "material `air` (materials[1])"
    );
}

/// An OS error names its path, and no message repeats its cause.
#[test]
fn os_errors_name_the_path_once() {
    let tmp = tempfile::tempdir().expect("tmp");
    let file = tmp.path().join("a_file");
    std::fs::write(&file, "not a folder").expect("write");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/two_disks.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_mpmice"))
        .args(["run", scene, "--quiet", "--out"])
        .arg(&file)
        .output()
        .expect("spawn");
    let err = String::from_utf8_lossy(&out.stderr);
    println!("{err}");
    assert!(!out.status.success());
    assert!(err.contains("a_file"), "{err}");
    let os = err
        .split(": ")
        .filter(|part| part.contains("os error"))
        .count();
    assert_eq!(os, 1, "the OS error once: {err}");
}

/// The watchdog's cell scan (a branch-free pass over each interior x-row,
/// then the per-cell search) finds each impossible value it checks, in
/// the first row's last cell and in a middle row, and passes the clean
/// state.
fn poison_every_cell_field<const D: usize>(scene: &Scene) {
    use mpmice::driver::model::Location;
    use mpmice::driver::models::arrays::cell_watchdog;
    let (s, _) = mpmice::scene::build_fluid_run::<D>(scene).expect("fluid");
    assert!(cell_watchdog(&s).is_none(), "the initial state is good");
    let (rows, n) = (&s.layout.rows, s.layout.cells[0]);
    type Poison<const D: usize> = fn(&mut mpmice::ice::IceState<D>, usize);
    let cases: [(&str, Poison<D>); 6] = [
        ("mass", |s, c| s.cells[0].mass[c] = -1e-300),
        ("velocity", |s, c| s.cells[0].velocity[c][D - 1] = f64::NAN),
        ("temperature (internal energy)", |s, c| {
            s.cells[0].temperature[c] = 0.0
        }),
        ("specific volume (1/density)", |s, c| {
            s.cells[0].sp_vol[c] = f64::INFINITY
        }),
        ("volume fraction", |s, c| s.cells[0].vol_frac[c] = f64::NAN),
        ("pressure", |s, c| s.pressure[c] = f64::NEG_INFINITY),
    ];
    for c in [rows[0] + n - 1, rows[rows.len() / 2] + n / 2] {
        for (field, poison) in cases {
            let mut bad = s.clone();
            poison(&mut bad, c);
            let v = cell_watchdog(&bad).unwrap_or_else(|| panic!("{field} at cell {c} missed"));
            assert_eq!(v.field, field);
            assert!(matches!(v.at, Location::Cell(k, _) if k == c), "{v}");
        }
    }
}

#[test]
fn the_cell_watchdog_finds_every_impossible_value() {
    poison_every_cell_field::<1>(&case("sod.toml"));
    // 3D: 200 × 2 × 2 cells, four interior x-rows.
    poison_every_cell_field::<3>(&case("sod_3d.toml"));
}

#[test]
fn the_particle_watchdog_finds_every_impossible_value() {
    use mpmice::driver::model::Location;
    use mpmice::driver::models::arrays::particle_watchdog;
    let mut run = mpmice::scene::build_solid_run::<2>(&case("two_disks.toml")).expect("solid");
    let n = run.particles.len();
    let mats = run.materials.clone();
    // Untracked optional arrays (an elastic run's temperature, plastic
    // strain and damage) pass; tracked, each entry is checked.
    assert!(run.particles.temperature.is_empty() && run.particles.damage.is_empty());
    assert!(particle_watchdog(&run.particles, &mats).is_none());
    run.particles.damage = vec![0.0; n];
    run.particles.track_temperature();
    run.particles.track_plastic_strain();
    assert!(particle_watchdog(&run.particles, &mats).is_none());
    type Poison = fn(&mut mpmice::mpm::Particles<2>, usize);
    let cases: [(&str, Poison); 9] = [
        ("position", |p, i| p.x[i][1] = f64::INFINITY),
        ("velocity", |p, i| p.v[i][0] = f64::NAN),
        ("mass", |p, i| p.mass[i] = 0.0),
        ("volume", |p, i| p.vol[i] = -1.0),
        ("J", |p, i| {
            let mut f = p.f.get(i);
            f[(0, 0)] = -f[(0, 0)];
            p.f.set(i, &f);
        }),
        ("stress", |p, i| {
            let mut s = p.stress.get(i);
            s[(2, 2)] = f64::NAN;
            p.stress.set(i, &s);
        }),
        ("temperature", |p, i| p.temperature[i] = f64::NAN),
        ("plastic_strain", |p, i| p.plastic_strain[i] = -1e-9),
        ("damage", |p, i| p.damage[i] = 1.5),
    ];
    // The first and last particle of the 4096-particle chunks the fast pass
    // sweeps, and the very last particle.
    for i in [0, 4095, 4096, n - 1] {
        for (field, poison) in cases {
            let mut p = run.particles.clone();
            poison(&mut p, i);
            let v = particle_watchdog(&p, &mats)
                .unwrap_or_else(|| panic!("{field} at particle {i} missed"));
            assert_eq!(v.field, field);
            assert!(matches!(v.at, Location::Particle(k) if k == i), "{v}");
            assert_eq!(v.material, "elastic");
        }
    }
    // A gas point's internal energy (York's Sod tube of gas points).
    let gas = mpmice::scene::build_solid_run::<2>(&case("york_sod.toml")).expect("gas");
    let mut p = gas.particles.clone();
    assert!(particle_watchdog(&p, &gas.materials).is_none());
    let i = p.len() / 2;
    p.work[i] = 0.0;
    let v = particle_watchdog(&p, &gas.materials).expect("found");
    assert_eq!((v.field, v.at), ("internal_energy", Location::Particle(i)));
}

/// A burn into a product that is only a trace in the gas beyond the face
/// (the tube holds air; the product is not in its region, so it starts at
/// the trace fraction 1e-10): the burn's step limit
/// ([`mpmice::coupling::reaction::MAX_GROWTH`]) collapses Δt, and the guard
/// names the burn, not a wave speed. The slab of `reaction_burn` (n = 0,
/// K = 1.8): the cell beyond its face (cell 50 of 250 on [0, 0.5]) is fed
/// at exactly K A = 1.8 kg/s per m².
#[test]
fn a_burn_into_a_trace_names_the_burn_that_limits_the_step() {
    let tmp = tempfile::tempdir().expect("tmp");
    let text = edit(
        &edit(
            &case_text("reaction_burn.toml"),
            "states = [{ material = \"products\", volume_fraction = 1.0, density = 0.4 }]",
            "states = [{ material = \"air\", volume_fraction = 1.0, temperature = 300.0 }]",
        ),
        "[[objects]]\nmaterial = \"pbx\"",
        "[[materials]]\nname = \"air\"\ntype = \"fluid\"\neos = \"ideal_gas\"\n\
         gamma = 1.4\ncv = 717.5\n\n[[objects]]\nmaterial = \"pbx\"",
    );
    let s = mpmice::scene::parse(&text).expect("parses");
    let e = check_scene(&s, &opts(tmp.path())).expect_err("refused");
    let msg = e.to_string();
    println!("{msg}");
    assert!(matches!(e, Error::Progress { step: 0, .. }), "{msg}");
    for part in [
        "Δt set by cell [50] of material `products`",
        "the burn of `pbx` feeds it 1.800e0 kg/s",
    ] {
        assert!(msg.contains(part), "`{part}` missing: {msg}");
    }
}
