//! Checkpoint / restart through the one run loop: a run stopped part-way and
//! continued from its checkpoint ends with outputs bit-identical to the
//! uninterrupted run, for every model; a checkpoint of another scene, a
//! damaged one or one of a newer format is rejected with a message that
//! says which; a run that blows up stops naming the site and leaves a
//! checkpoint of the last good state.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use mpmice::driver::{run_scene, RunOptions, Summary};
use mpmice::error::Error;
use mpmice::scene::Scene;

fn case(name: &str) -> Scene {
    let path = format!("{}/cases/{name}", env!("CARGO_MANIFEST_DIR"));
    mpmice::scene::load(Path::new(&path)).expect("case parses")
}

fn opts(dir: &Path) -> RunOptions {
    RunOptions::quiet(dir, 2)
}

/// Every output file of a run folder (checkpoints and the summary apart),
/// by name.
fn outputs(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    for e in std::fs::read_dir(dir).expect("run folder") {
        let e = e.expect("entry");
        let name = e.file_name().to_string_lossy().into_owned();
        if e.path().is_file() && name != "summary.json" {
            files.insert(name, std::fs::read(e.path()).expect("read"));
        }
    }
    files
}

/// The checkpoint folders of a run, oldest first.
fn checkpoints(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir.join("checkpoints"))
        .map(|r| r.map(|e| e.expect("entry").path()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

/// The summary's numbers that must not depend on the interruption.
fn physics(s: &Summary) -> Vec<u64> {
    let mut v = vec![
        s.steps,
        s.final_time.to_bits(),
        s.dt_min.to_bits(),
        s.dt_max.to_bits(),
        s.mass_drift.to_bits(),
        s.momentum_drift.to_bits(),
        s.energy_drift.to_bits(),
        s.final_energy.total().to_bits(),
        s.retries,
    ];
    if let Some(it) = &s.iterations {
        v.extend([
            it.nonlinear_mean.to_bits(),
            it.linear_mean.to_bits(),
            it.nonlinear_max as u64,
            it.linear_max as u64,
        ]);
    }
    v
}

/// Runs `scene` uninterrupted; then again, stopped (step limit) after a
/// checkpoint near half time, and restarted from that checkpoint; asserts
/// that both end with byte-identical outputs and summary numbers.
fn assert_restart_is_bit_identical(label: &str, scene: &Scene) {
    let tmp = tempfile::tempdir().expect("tmp");
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let full = run_scene(scene, &opts(&a)).expect("uninterrupted run");
    assert!(full.steps >= 4, "{label}: {} steps", full.steps);

    let mut first = scene.clone();
    first.output.checkpoint_interval = Some(0.5 * scene.time.end);
    first.time.max_steps = Some(full.steps - 1);
    let part = run_scene(&first, &opts(&b)).expect("first part");
    assert_eq!(part.steps, full.steps - 1, "{label}: first part steps");
    let cks = checkpoints(&b);
    assert_eq!(cks.len(), 1, "{label}: checkpoints {cks:?}");
    let restart = RunOptions {
        restart: Some(cks[0].clone()),
        ..opts(&b)
    };
    let rest = run_scene(scene, &restart).expect("restarted run");

    assert_eq!(physics(&full), physics(&rest), "{label}: summary numbers");
    let (fa, fb) = (outputs(&a), outputs(&b));
    assert_eq!(
        fa.keys().collect::<Vec<_>>(),
        fb.keys().collect::<Vec<_>>(),
        "{label}: output files"
    );
    for (name, bytes) in &fa {
        assert!(bytes == &fb[name], "{label}: {name} differs after restart");
    }
    println!(
        "{label}: {} steps, restarted at step {} of the checkpoint {}; {} files identical",
        full.steps,
        cks[0].file_name().unwrap().to_string_lossy(),
        cks[0].display(),
        fa.len()
    );
}

#[test]
fn explicit_solid_restarts_bit_identically() {
    let mut s = case("two_disks.toml");
    s.grid.cells = vec![24, 24];
    s.time.end = 1.6;
    s.output.interval = Some(0.4);
    assert_restart_is_bit_identical("explicit solid", &s);
}

#[test]
fn implicit_solid_restarts_bit_identically() {
    // Quasistatic load steps with a prescribed grip.
    assert_restart_is_bit_identical("implicit quasistatic", &case("bar_stretch_impm.toml"));
    // Newmark dynamics with Δt control: the disks collide.
    let mut s = case("two_disks.toml");
    s.grid.cells = vec![16, 16];
    s.time.mode = mpmice::scene::Mode::Implicit;
    s.time.end = 1.5;
    s.time.dt = Some(0.05);
    s.implicit.dynamic = true;
    s.output.interval = Some(0.5);
    assert_restart_is_bit_identical("implicit Newmark", &s);
}

#[test]
fn ice_restarts_bit_identically() {
    let mut s = case("sod.toml");
    s.grid.cells = vec![200];
    assert_restart_is_bit_identical("ICE explicit (high resolution)", &s);
    let mut s = case("sod_semi_implicit.toml");
    s.grid.cells = vec![200];
    s.output.interval = Some(0.05);
    assert_restart_is_bit_identical("ICE semi-implicit", &s);
    let mut s = case("shock_helium_bubble.toml");
    s.grid.cells = vec![40, 20];
    s.time.end = 0.2;
    assert_restart_is_bit_identical("ICE 2D two materials", &s);
}

#[test]
fn coupled_restarts_bit_identically() {
    let mut s = case("piston.toml");
    s.time.end = 0.02;
    s.output.interval = Some(0.005);
    assert_restart_is_bit_identical("coupled piston (explicit)", &s);
    // The first 2 of the case's 8 ms, inside the heat source's 3 ms.
    let mut s = case("pressurized_cylinder.toml");
    s.time.end = 0.002;
    s.output.interval = Some(0.0005);
    assert_restart_is_bit_identical("coupled cylinder (explicit, heat source)", &s);
    s.time.mode = mpmice::scene::Mode::SemiImplicit;
    assert_restart_is_bit_identical("coupled cylinder (semi-implicit)", &s);
    let s = case("pressurized_cylinder_implicit.toml");
    assert_restart_is_bit_identical("coupled cylinder (implicit, quasistatic)", &s);
    let mut s = case("pressurized_cylinder_implicit.toml");
    s.implicit.dynamic = true;
    assert_restart_is_bit_identical("coupled cylinder (implicit, Newmark)", &s);
}

#[test]
fn reactions_restart_bit_identically() {
    // A fast surface burn (cases/reaction_burn.toml with K = 2e5): the
    // reaction totals, each reaction's step limit and the particles that
    // burnt out (removed) travel in the checkpoint.
    let mut s = case("reaction_burn.toml");
    s.reactions[0].rate_constant = 2e5;
    s.time.end = 6e-5;
    s.output.interval = Some(2e-5);
    assert_restart_is_bit_identical("surface burn", &s);
}

#[test]
fn gas_points_restart_bit_identically() {
    // York Sod with gas material points (explicit MPM model): the gas
    // state (stress, internal energy in `work`, J) travels in the
    // checkpoint's particle arrays.
    let mut s = case("york_sod.toml");
    s.grid.cells = vec![50, 1];
    s.grid.upper[1] = 0.02;
    for o in &mut s.objects {
        if let mpmice::scene::Geometry::Box { upper, .. } = &mut o.geometry {
            upper[1] = 0.02;
        }
    }
    s.time.end = 0.05;
    s.output.interval = Some(0.025);
    assert_restart_is_bit_identical("gas points (York Sod)", &s);
}

#[test]
fn multiphase_restarts_bit_identically() {
    // Zhang's multiphase model: every phase's points travel in the
    // checkpoint; the nodal fields are rebuilt from them at the next step.
    // A tungsten square through air with drag (the phase leaves nodes,
    // the gas is compressed) and the block test moving diagonally.
    let mut s = case("zhang_tungsten_air.toml");
    s.time.end = 4e-4;
    s.output.interval = Some(1e-4);
    assert_restart_is_bit_identical("multiphase tungsten/air", &s);
    let mut s = case("zhang_block.toml");
    s.grid.cells = vec![10, 10];
    s.time.end = 0.01;
    s.output.interval = Some(0.005);
    assert_restart_is_bit_identical("multiphase block", &s);
}

#[test]
fn failing_solids_restart_bit_identically() {
    // The spall bar (the centre fails at 66 us), checkpointed at 70 us
    // (after: the damage and the failed points' stress travel in the
    // checkpoint) and at 60 us (before: the damage array is there, zero).
    let mut s = case("tensile_bar_spall.toml");
    s.time.end = 1.4e-4;
    assert_restart_is_bit_identical("spall bar, checkpoint after the spall", &s);
    let s = case("tensile_bar_spall.toml");
    assert_restart_is_bit_identical("spall bar, checkpoint before the spall", &s);
}

#[test]
fn membranes_restart_bit_identically() {
    // York dog-bone (membrane + gas points) on the coarsest grid, briefly:
    // the membrane stress, stretch (volume) and strain energy (work) travel
    // in the particle arrays; the chains and initial segment lengths come
    // from the scene and the tangents are recomputed every step.
    let mut s = case("york_dogbone.toml");
    s.grid.cells = vec![12, 12];
    s.objects[0].spacing = Some(0.1);
    s.time.end = 0.02;
    s.output.interval = Some(0.01);
    assert_restart_is_bit_identical("membrane (York dog-bone)", &s);
}

/// Runs `scene` to a checkpoint and returns it (the run stops by its step
/// limit after the checkpoint).
#[test]
fn membrane_elements_restart_bit_identically() {
    // Lian's membrane elements: node positions and velocities, element
    // stress (co-rotational frame), thickness, normals and the energy
    // accumulators travel in the checkpoint; masses, fixed nodes and loads
    // come from the scene.
    let mut s = case("lian_membrane_vibration.toml");
    if let mpmice::scene::MeshSpec::Rectangle { cells, .. } = &mut s.membrane_elements[0].mesh {
        *cells = [8, 8];
    }
    s.time.end = 0.2;
    s.output.interval = Some(0.05);
    assert_restart_is_bit_identical("membrane elements (Lian vibration)", &s);
}

fn a_checkpoint(scene: &Scene, dir: &Path) -> PathBuf {
    let mut s = scene.clone();
    s.output.checkpoint_interval = Some(0.25 * s.time.end);
    s.time.max_steps = Some(40);
    run_scene(&s, &opts(dir)).expect("run");
    checkpoints(dir).pop().expect("a checkpoint")
}

fn restart_error(scene: &Scene, ck: &Path, dir: &Path) -> String {
    let o = RunOptions {
        restart: Some(ck.to_path_buf()),
        ..opts(dir)
    };
    match run_scene(scene, &o) {
        Ok(_) => panic!("restart from {} accepted", ck.display()),
        Err(e @ Error::Checkpoint(_)) => e.to_string(),
        Err(e) => panic!("not a checkpoint error: {e}"),
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for e in std::fs::read_dir(from).expect("read") {
        let e = e.expect("entry");
        std::fs::copy(e.path(), to.join(e.file_name())).expect("copy");
    }
}

#[test]
fn bad_checkpoints_are_rejected_with_the_reason() {
    let tmp = tempfile::tempdir().expect("tmp");
    let mut scene = case("sod.toml");
    scene.grid.cells = vec![100];
    let ck = a_checkpoint(&scene, &tmp.path().join("run"));
    let out = tmp.path().join("restart");

    // Another scene (other physics: the CFL number).
    let mut other = scene.clone();
    other.time.cfl = 0.3;
    let msg = restart_error(&other, &ck, &out);
    assert!(msg.contains("another scene"), "{msg}");
    // Outputs and end time may change: that is the same scene.
    let mut longer = scene.clone();
    longer.time.end = 0.25;
    longer.output.interval = None;
    let o = RunOptions {
        restart: Some(ck.clone()),
        ..opts(&tmp.path().join("longer"))
    };
    let s = run_scene(&longer, &o).expect("a longer run of the same scene");
    assert_eq!(s.final_time, 0.25);

    // A model of another kind with the same hash cannot happen; a
    // truncated array, a flipped byte and a newer format can.
    let damaged = |tag: &str, f: &dyn Fn(&Path)| -> String {
        let d = tmp.path().join(tag);
        copy_dir(&ck, &d);
        f(&d);
        restart_error(&scene, &d, &out)
    };
    let array = "cells.m0.mass.npy";
    let msg = damaged("truncated", &|d| {
        let p = d.join(array);
        let bytes = std::fs::read(&p).expect("read");
        std::fs::write(&p, &bytes[..bytes.len() - 100]).expect("write");
    });
    assert!(msg.contains("truncated") && msg.contains(array), "{msg}");
    let msg = damaged("flipped", &|d| {
        let p = d.join(array);
        let mut bytes = std::fs::read(&p).expect("read");
        let k = bytes.len() - 3;
        bytes[k] ^= 0x40;
        std::fs::write(&p, &bytes).expect("write");
    });
    assert!(msg.contains("checksum") && msg.contains(array), "{msg}");
    let msg = damaged("newer", &|d| {
        let p = d.join("manifest.json");
        let text = std::fs::read_to_string(&p).expect("read");
        let text = text.replace("\"format_version\": 1", "\"format_version\": 7");
        std::fs::write(&p, text).expect("write");
    });
    assert!(msg.contains("version 7"), "{msg}");
    let msg = damaged("missing", &|d| {
        std::fs::remove_file(d.join(array)).expect("rm");
    });
    assert!(msg.contains(array), "{msg}");
    let msg = restart_error(&scene, &tmp.path().join("nowhere"), &out);
    assert!(msg.contains("nowhere"), "{msg}");
}

/// Runs `s` (in `tmp/run`) into a failure that must stop with a checkpoint,
/// checks that the checkpoint reads back at the stop's step and that a
/// restart from it (in `tmp/again`) fails the same way; returns the message
/// and the checkpoint's step.
fn stop_and_restart(s: &Scene, tmp: &Path) -> (String, u64) {
    let err = run_scene(s, &opts(&tmp.join("run"))).expect_err("must fail");
    let msg = err.to_string();
    println!("{msg}");
    let Error::Stopped {
        checkpoint, step, ..
    } = &err
    else {
        panic!("not a stop with a checkpoint: {msg}");
    };
    // The checkpoint holds a state the watchdog passed; it restarts into
    // the same failure, named the same way.
    let ck = mpmice::output::checkpoint::Checkpoint::read(checkpoint, None).expect("readable");
    assert_eq!(ck.step(), *step);
    let again = run_scene(
        s,
        &RunOptions {
            restart: Some(checkpoint.clone()),
            ..opts(&tmp.join("again"))
        },
    )
    .expect_err("fails again");
    assert_eq!(
        msg.split(';').next(),
        again.to_string().split(';').next(),
        "the same failure after a restart"
    );
    (msg, *step)
}

#[test]
fn a_blow_up_names_the_site_and_keeps_the_last_good_state() {
    // Explicit MPM at 40 times its stable step: the disks invert.
    let tmp = tempfile::tempdir().expect("tmp");
    let mut s = case("two_disks.toml");
    s.grid.cells = vec![16, 16];
    s.time.dt = Some(0.2);
    s.time.watchdog_interval = 1;
    s.output.interval = Some(0.4);
    let dir = tmp.path().join("run");
    let (msg, _) = stop_and_restart(&s, tmp.path());
    assert!(msg.contains("step") && msg.contains("t = "), "{msg}");
    assert!(
        msg.contains("particle") && msg.contains("`elastic`"),
        "names particle and material: {msg}"
    );
    // Every output file parses: the summary names the error.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary"))
            .expect("json");
    assert!(summary["error"]
        .as_str()
        .is_some_and(|e| e.contains("step")));
    assert!(std::fs::read_to_string(dir.join("history.csv"))
        .expect("history")
        .ends_with('\n'));
}

/// An explicit solid that puts a NaN into one particle's velocity after a
/// given step (as a blow-up would), to exercise the watchdog.
struct Poisoned {
    inner: mpmice::driver::models::ExplicitSolid<2>,
    at_step: u64,
}

impl mpmice::driver::Model for Poisoned {
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
    fn step(&mut self, dt: mpmice::driver::DtRequest) -> Result<mpmice::driver::StepStats, Error> {
        let st = self.inner.step(dt)?;
        if self.inner.steps() == self.at_step {
            self.inner.run.particles.v[17][1] = f64::NAN;
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
}

#[test]
fn the_watchdog_stops_a_nan_and_keeps_the_last_checked_state() {
    let tmp = tempfile::tempdir().expect("tmp");
    let mut s = case("two_disks.toml");
    s.grid.cells = vec![16, 16];
    // (watchdog interval, NaN after step, found after step, saved step): the
    // scan runs every `interval` steps and keeps the state it passed.
    for (interval, at_step, expect_found, expect_saved) in
        [(5u64, 25u64, 25u64, 20u64), (5, 5, 5, 0), (1, 7, 7, 6)]
    {
        s.time.watchdog_interval = interval;
        let mut m = Poisoned {
            inner: mpmice::driver::models::ExplicitSolid {
                run: mpmice::scene::build_solid_run::<2>(&s).expect("build"),
            },
            at_step,
        };
        let dir = tmp.path().join(format!("at{at_step}_{interval}"));
        let err = mpmice::driver::run_model(&mut m, &s, &opts(&dir), 2).expect_err("stops");
        let msg = err.to_string();
        println!("{msg}");
        let Error::Stopped {
            cause,
            step,
            checkpoint,
            ..
        } = &err
        else {
            panic!("{msg}");
        };
        assert!(
            matches!(**cause, Error::Watchdog { step, .. } if step == expect_found),
            "{msg}"
        );
        assert!(
            msg.contains("particle 17") && msg.contains("`elastic`") && msg.contains("velocity"),
            "{msg}"
        );
        assert_eq!(*step, expect_saved, "{msg}");
        let mut ck =
            mpmice::output::checkpoint::Checkpoint::read(checkpoint, None).expect("readable");
        let v = ck.take_f64("particles.v", None).expect("velocities");
        assert!(v.iter().all(|x| x.is_finite()), "the saved state is good");
        // The last good state kept on disk instead (`time.last_good`, what a
        // large run does): the same checkpoint file for file, the same last
        // snapshot, and no working copy left behind.
        let mut on_disk = s.clone();
        on_disk.time.last_good = mpmice::scene::LastGood::Disk;
        let mut m = Poisoned {
            inner: mpmice::driver::models::ExplicitSolid {
                run: mpmice::scene::build_solid_run::<2>(&on_disk).expect("build"),
            },
            at_step,
        };
        let disk_dir = tmp.path().join(format!("at{at_step}_{interval}_disk"));
        let err2 =
            mpmice::driver::run_model(&mut m, &on_disk, &opts(&disk_dir), 2).expect_err("stops");
        let Error::Stopped {
            checkpoint: ck2, ..
        } = &err2
        else {
            panic!("{err2}");
        };
        let files = |d: &std::path::Path| {
            let mut v: Vec<_> = std::fs::read_dir(d)
                .expect("dir")
                .map(|e| e.expect("entry").file_name())
                .collect();
            v.sort();
            v
        };
        assert_eq!(files(checkpoint), files(ck2));
        for f in files(checkpoint) {
            assert!(
                std::fs::read(checkpoint.join(&f)).expect("a")
                    == std::fs::read(ck2.join(&f)).expect("b"),
                "{f:?} differs"
            );
        }
        let last_snapshot = |d: &std::path::Path| {
            let mut csv: Vec<_> = files(d)
                .into_iter()
                .filter(|f| f.to_string_lossy().starts_with("particles_"))
                .collect();
            csv.sort();
            std::fs::read(d.join(csv.last().expect("a snapshot"))).expect("snapshot")
        };
        assert!(
            last_snapshot(&dir) == last_snapshot(&disk_dir),
            "the restored snapshot"
        );
        assert!(!disk_dir.join(mpmice::driver::LAST_GOOD_DIR).exists());
    }
}

#[test]
fn a_fluid_torn_to_vacuum_names_the_cell_and_material_and_keeps_the_last_good_state() {
    // Two streams of gas leaving the middle at Mach ~40: explicit ICE drives
    // a cell's temperature through zero within a few hundred steps.
    let tmp = tempfile::tempdir().expect("tmp");
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/sod.toml"))
        .expect("case");
    let right =
        "pressure = 0.1\nstates = [{ material = \"gas\", volume_fraction = 1.0, density = 0.125 }]";
    let left =
        "pressure = 1.0\nstates = [{ material = \"gas\", volume_fraction = 1.0, density = 1.0 }]";
    assert!(text.contains(right) && text.contains(left));
    let text = text
        .replace(right, "pressure = 0.4\nstates = [{ material = \"gas\", volume_fraction = 1.0, density = 1.0, velocity = [50.0] }]")
        .replace(left, "pressure = 0.4\nstates = [{ material = \"gas\", volume_fraction = 1.0, density = 1.0, velocity = [-50.0] }]");
    let path = tmp.path().join("vacuum.toml");
    std::fs::write(&path, text).expect("write");
    let mut s = mpmice::scene::load(&path).expect("scene");
    s.time.watchdog_interval = 5;
    let (msg, step) = stop_and_restart(&s, tmp.path());
    for part in ["step ", "t = ", "cell [", "material `gas`", "temperature"] {
        assert!(msg.contains(part), "`{part}` missing: {msg}");
    }
    // The checkpoint is the last state the watchdog passed (every 5 steps).
    assert_eq!(step % 5, 0);
}

#[test]
fn membrane_contact_restarts_bit_identically() {
    // Lian's sphere on a clamped membrane, coarse: the history's contact
    // totals (impulse, dissipated energy) resume from the checkpoint.
    let mut s = case("lian_sphere_on_membrane.toml");
    s.grid.cells = vec![13, 13, 15];
    if let Some(mpmice::scene::MeshSpec::Rectangle { cells, .. }) =
        s.membrane_elements.first_mut().map(|m| &mut m.mesh)
    {
        *cells = [13, 13];
    }
    s.time.end = 2e-4;
    s.output.interval = Some(1e-4);
    assert_restart_is_bit_identical("membrane contact", &s);
}
