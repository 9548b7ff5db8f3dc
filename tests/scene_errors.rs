//! Bad scene input is rejected with the key path and the allowed values,
//! never a panic — through the library and through the `mpmice` binary.

use std::process::Command;

const GOOD: &str = r#"
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
"#;

/// The good scene with `from` replaced by `to` (which must occur once).
fn edit(from: &str, to: &str) -> String {
    assert_eq!(GOOD.matches(from).count(), 1, "edit anchor `{from}`");
    GOOD.replacen(from, to, 1)
}

/// Every `(scene text, key path, word)` must be rejected naming that key
/// path with the word in its message — by `check` as by `run`, through the
/// library (parsing, then everything `run` checks before its first step)
/// and through both verbs of the binary; all mismatches are reported at
/// once.
fn assert_each_names_its_key(cases: &[(String, &str, &str)]) {
    let mut wrong = Vec::new();
    let tmp = tempfile::tempdir().expect("tmp");
    for (k, (text, path, word)) in cases.iter().enumerate() {
        let verdict = mpmice::scene::parse(text).map_err(mpmice::error::Error::Scene);
        let verdict = verdict.and_then(|s| {
            mpmice::driver::check_scene(&s, &mpmice::driver::RunOptions::default()).map(|_| ())
        });
        match verdict {
            Ok(()) => wrong.push(format!("accepted, expected `{path}`")),
            Err(mpmice::error::Error::Scene(e)) if e.path == *path && e.message.contains(word) => {}
            Err(e) => wrong.push(format!("expected `{path}` with `{word}`, got: {e}")),
        }
        let file = tmp.path().join(format!("case{k}.toml"));
        std::fs::write(&file, text).expect("write");
        for verb in ["check", "run"] {
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_mpmice"));
            cmd.arg(verb).arg(&file);
            if verb == "run" {
                cmd.arg("--quiet")
                    .arg("--out")
                    .arg(tmp.path().join(format!("out{k}")));
            }
            let out = cmd.output().expect("spawn");
            let err = String::from_utf8_lossy(&out.stderr);
            if out.status.success()
                || !err.contains(&format!("`{path}`"))
                || err.contains("panicked")
            {
                wrong.push(format!("{verb} of `{path}` case: {err}"));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn the_good_scene_is_accepted() {
    let s = mpmice::scene::parse(GOOD).expect("valid");
    assert_eq!(s.grid.dim, 2);
}

#[test]
fn each_bad_input_names_its_key_and_the_allowed_values() {
    // (edit, expected key path, a word of the message)
    let cases: &[(String, &str, &str)] = &[
        (
            edit("cfl = 0.5", "cfl = 0.5\nstep_size = 2"),
            "time.step_size",
            "unknown field `step_size`",
        ),
        (
            edit("density = 7800.0", "densty = 7800.0"),
            "materials[0].densty",
            "expected one of",
        ),
        (edit("end = 0.1\n", ""), "time", "missing field `end`"),
        (
            edit("cfl = 0.5", "cfl = 0.5\nlast_good = \"ram\""),
            "time.last_good",
            "`auto`, `memory`, `disk`",
        ),
        (
            edit(
                "poisson_ratio = 0.3",
                "poisson_ratio = 0.3\nmin_pressure = 0.0",
            ),
            "materials[0].min_pressure",
            "only for fluid materials",
        ),
        (
            edit("end = 0.1", "end = \"soon\""),
            "time.end",
            "invalid type",
        ),
        (
            edit("density = 7800.0", "density = -1.0"),
            "materials[0].density",
            "> 0",
        ),
        (
            edit("youngs_modulus = 200e9", "youngs_modulus = 0.0"),
            "materials[0].youngs_modulus",
            "> 0",
        ),
        (
            edit("poisson_ratio = 0.3", "poisson_ratio = 0.5"),
            "materials[0].poisson_ratio",
            "0.5",
        ),
        (
            edit("upper = [0.8, 0.8]", "upper = [1.2, 0.8]"),
            "objects[0].geometry",
            "outside the grid",
        ),
        (
            edit(
                r#"geometry = { type = "box", lower = [0.2, 0.2], upper = [0.8, 0.8] }"#,
                r#"geometry = { type = "intersection", parts = [] }"#,
            ),
            "objects[0].geometry.parts",
            "at least one region",
        ),
        (
            edit(
                r#"geometry = { type = "box", lower = [0.2, 0.2], upper = [0.8, 0.8] }"#,
                r#"geometry = { type = "intersection", parts = [
                    { type = "box", lower = [0.2, 0.2], upper = [0.8, 0.8] },
                    { type = "annulus", center = [0.0, 0.0], inner_radius = 0.5, outer_radius = 0.4 },
                ] }"#,
            ),
            "objects[0].geometry.parts[1].outer_radius",
            "must be > inner_radius",
        ),
        (
            edit(
                r#"geometry = { type = "box", lower = [0.2, 0.2], upper = [0.8, 0.8] }"#,
                r#"geometry = { type = "intersection", parts = [
                    { type = "box", lower = [0.2, 0.2], upper = [0.1, 0.8] },
                ] }"#,
            ),
            "objects[0].geometry.parts[0].upper[0]",
            "must be > lower[0]",
        ),
        (
            edit(
                r#"geometry = { type = "box", lower = [0.2, 0.2], upper = [0.8, 0.8] }"#,
                r#"geometry = { type = "intersection", parts = [
                    { type = "half_space", point = [0.5, 0.5], normal = [0.0, 0.0] },
                ] }"#,
            ),
            "objects[0].geometry.parts[0].normal",
            "must not be zero",
        ),
        (edit("cfl = 0.5", "cfl = 0.0"), "time.cfl", "0 < cfl ≤ 1"),
        (edit("cfl = 0.5", "cfl = 1.5"), "time.cfl", "0 < cfl ≤ 1"),
        (
            edit("cells = [10, 10]", "cells = [10, 0]"),
            "grid.cells[1]",
            "≥ 1",
        ),
        (edit("dim = 2", "dim = 4"), "grid.dim", "1, 2 or 3"),
        (
            edit("cells = [10, 10]", "cells = [10]"),
            "grid.cells",
            "2 components",
        ),
        (
            edit("model = \"linear_elastic\"", "model = \"rubbery\""),
            "materials[0].model",
            "neo_hookean",
        ),
        (
            edit("x_lower = \"fixed\"", "x_lower = \"sticky\""),
            "grid.boundary.x_lower",
            "symmetry",
        ),
        (
            edit("material = \"steel\"", "material = \"wood\""),
            "objects[0].material",
            "unknown material",
        ),
        (
            edit("cfl = 0.5", "cfl = 0.5\nmode = \"semi_implicit\""),
            "time.mode",
            "explicit, implicit",
        ),
        (
            edit("cfl = 0.5", "cfl = 0.5\nmode = \"implicit\""),
            "time.dt",
            "first timestep",
        ),
        (
            edit(
                "[[materials]]",
                "[implicit]\nmax_newton_iterations = 0\n\n[[materials]]",
            ),
            "implicit.max_newton_iterations",
            "≥ 1",
        ),
        (
            edit(
                "[[materials]]",
                "[implicit]\ntolerance_displacement = 0.0\n\n[[materials]]",
            ),
            "implicit.tolerance_displacement",
            "> 0",
        ),
        (
            edit(
                "[[materials]]",
                "[implicit]\nlinear_solver = \"magic\"\n\n[[materials]]",
            ),
            "implicit.linear_solver",
            "cholesky",
        ),
        (
            edit(
                "[[materials]]",
                "[implicit]\nhold_solid_faces = true\n\n[[materials]]",
            ),
            "implicit.hold_solid_faces",
            "dynamic = false",
        ),
        (
            edit(
                "velocity = [1.0, 0.0]",
                "velocity = [1.0, 0.0]\ninner_pressure = 1e6",
            ),
            "objects[0].inner_pressure",
            "annulus",
        ),
        (
            edit("type = \"box\"", "type = \"cone\""),
            "objects[0].geometry.type",
            "box",
        ),
        (edit("end = 0.1", "end = 0.1\ndt = -1.0"), "time.dt", "> 0"),
        (
            edit("[[materials]]", "[mpm]\ndamping = -2.0\n\n[[materials]]"),
            "mpm.damping",
            "≥ 0",
        ),
        (
            edit(
                "[[materials]]",
                "[mpm]\npic_fraction = 1.5\n\n[[materials]]",
            ),
            "mpm.pic_fraction",
            "0 (FLIP) … 1 (PIC)",
        ),
        (
            edit(
                "cfl = 0.5",
                "cfl = 0.5\nmode = \"implicit\"\ndt = 0.01\n\n[mpm]\npic_fraction = 0.1",
            ),
            "mpm.pic_fraction",
            "explicit",
        ),
        ("this is = not toml [".to_string(), "<toml>", "TOML"),
        // Failure models (issue 18; more in tests/failure.rs).
        (
            edit(
                "poisson_ratio = 0.3\n",
                "poisson_ratio = 0.3\nfailure = { model = \"tensile\", spall_strength = -5e8 }\n",
            ),
            "materials[0].failure.spall_strength",
            "> 0",
        ),
        (
            edit(
                "poisson_ratio = 0.3\n",
                "poisson_ratio = 0.3\nplasticity = { flow = \"linear\", yield_stress = 3e8 }\n\
                 failure = { model = \"johnson_cook\", d1 = -0.5, d2 = 0.5, d3 = -1.0 }\n",
            ),
            "materials[0].failure.d1",
            "d1 + d2 > 0",
        ),
        (
            edit(
                "poisson_ratio = 0.3\n",
                "poisson_ratio = 0.3\nfailure = { model = \"johnson_cook\", d1 = 0.5, d2 = 0.5, \
                 d3 = -1.0 }\n",
            ),
            "materials[0].failure",
            "plasticity",
        ),
    ];
    assert_each_names_its_key(cases);
}

#[test]
fn the_cli_rejects_bad_scenes_without_panicking() {
    let dir = tempfile::tempdir().expect("tmp");
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, edit("poisson_ratio = 0.3", "poisson_ratio = 0.7")).expect("write");
    for sub in ["check", "run"] {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_mpmice"));
        cmd.arg(sub).arg(&bad);
        if sub == "run" {
            cmd.arg("--out").arg(dir.path().join("out")).arg("--quiet");
        }
        let out = cmd.output().expect("spawn");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{sub}: must fail");
        assert!(err.contains("materials[0].poisson_ratio"), "{sub}: {err}");
        assert!(!err.contains("panicked"), "{sub}: {err}");
    }
    let out = Command::new(env!("CARGO_BIN_EXE_mpmice"))
        .args(["check", "/no/such/scene.toml"])
        .output()
        .expect("spawn");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read"));
}

#[test]
fn the_cli_checks_and_runs_the_default_scene() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/two_disks.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_mpmice"))
        .args(["check", scene])
        .output()
        .expect("spawn");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

const FLUID: &str = r#"
[grid]
dim = 1
lower = [0.0]
upper = [1.0]
cells = [50]
boundary = { x_lower = "fixed", x_upper = "fixed" }

[time]
end = 0.1

[fluid]
exchange = { momentum = 1e15 }

[[materials]]
name = "air"
type = "fluid"
eos = "ideal_gas"
gamma = 1.4
cv = 717.5

[[materials]]
name = "water"
type = "fluid"
eos = "stiffened_gas"
gamma = 4.4
cv = 2588.3
p_inf = 6e8

[[regions]]
pressure = 1e5
states = [{ material = "air", volume_fraction = 1.0, temperature = 300.0 }]

[[regions]]
geometry = { type = "box", lower = [0.5], upper = [1.0] }
pressure = 1e5
states = [
  { material = "water", volume_fraction = 0.9, density = 1000.0 },
  { material = "air", volume_fraction = 0.1, temperature = 300.0 },
]
"#;

fn fluid_edit(from: &str, to: &str) -> String {
    assert_eq!(FLUID.matches(from).count(), 1, "edit anchor `{from}`");
    FLUID.replacen(from, to, 1)
}

/// Periodic faces with the multigrid pressure solver are accepted on an
/// even grid and on an odd one small enough to be the multigrid's directly
/// solved coarsest level (the odd large grid is in the error table).
#[test]
fn periodic_pcg_multigrid_is_accepted() {
    for cells in [2048, 127] {
        let s = fluid_edit(
            "cells = [50]\nboundary = { x_lower = \"fixed\", x_upper = \"fixed\" }",
            &format!(
                "cells = [{cells}]\nboundary = {{ x_lower = \"periodic\", x_upper = \"periodic\" }}\n\n\
                 [fluid.pressure]\nsolver = \"pcg_multigrid\""
            ),
        )
        // The pressure solve runs in semi-implicit mode only.
        .replacen("end = 0.1", "end = 0.1\nmode = \"semi_implicit\"", 1);
        if let Err(e) = mpmice::scene::parse(&s) {
            panic!("{cells} cells: {e}");
        }
    }
}

#[test]
fn the_fluid_scene_is_accepted_and_runs() {
    let s = mpmice::scene::parse(FLUID).expect("valid");
    let dir = tempfile::tempdir().expect("tmp");
    let sum = mpmice::driver::run_scene(&s, &mpmice::driver::RunOptions::quiet(dir.path(), 1))
        .expect("run");
    // Air/water at one pressure and at rest in a closed box stays at rest
    // (no spurious flow at the material interface) and keeps its mass.
    eprintln!(
        "air/water at rest: {} steps, kinetic/internal {:.3e}, mass drift {:.3e}",
        sum.steps,
        sum.final_energy.kinetic / sum.final_energy.strain,
        sum.mass_drift
    );
    assert!(sum.final_energy.kinetic < 1e-12 * sum.final_energy.strain);
    assert!(sum.mass_drift.abs() < 1e-13);
}

#[test]
fn bad_fluid_input_names_its_key() {
    let cases: &[(String, &str, &str)] = &[
        (
            fluid_edit("eos = \"ideal_gas\"", "eos = \"van_der_waals\""),
            "materials[0].eos",
            "stiffened_gas",
        ),
        (
            fluid_edit("gamma = 1.4", "gamma = 1.0"),
            "materials[0].gamma",
            "> 1",
        ),
        (
            fluid_edit("cv = 717.5", "cv = 0.0"),
            "materials[0].cv",
            "> 0",
        ),
        (
            fluid_edit("p_inf = 6e8", "p_inf = -1.0"),
            "materials[1].p_inf",
            "≥ 0",
        ),
        (
            fluid_edit("density = 1000.0", "density = -1000.0"),
            "regions[1].states[0].density",
            "> 0",
        ),
        (
            fluid_edit(
                "pressure = 1e5\nstates = [{",
                "pressure = -1e5\nstates = [{",
            ),
            "regions[0].pressure",
            "> 0",
        ),
        (
            fluid_edit("volume_fraction = 0.9", "volume_fraction = 0.8"),
            "regions[1].states",
            "sum to 1",
        ),
        (
            fluid_edit("gamma = 1.4", "gamma = 1.4\ndensity = 1.2"),
            "materials[0].density",
            "regions",
        ),
        (
            fluid_edit("material = \"water\"", "material = \"oil\""),
            "regions[1].states[0].material",
            "unknown fluid",
        ),
        (
            fluid_edit("x_lower = \"fixed\"", "x_lower = \"periodic\""),
            "grid.boundary.x_lower",
            "both faces",
        ),
        (
            fluid_edit("end = 0.1", "end = 0.1\nmode = \"implicit\""),
            "time.mode",
            "semi_implicit",
        ),
        (
            fluid_edit(
                "[fluid]",
                "[fluid.pressure]\nsolver = \"gauss_seidel\"\n\n[fluid]",
            ),
            "fluid.pressure.solver",
            "pcg_multigrid",
        ),
        (
            fluid_edit(
                "cells = [50]\nboundary = { x_lower = \"fixed\", x_upper = \"fixed\" }",
                "cells = [129]\nboundary = { x_lower = \"periodic\", x_upper = \"periodic\" }\n\n\
                 [fluid.pressure]\nsolver = \"pcg_multigrid\"",
            ),
            "fluid.pressure.solver",
            "even number of cells",
        ),
        (
            fluid_edit(
                "[fluid]",
                "[fluid.pressure]\nlinear_tolerance = 0.0\n\n[fluid]",
            ),
            "fluid.pressure.linear_tolerance",
            "(0, 1)",
        ),
        (
            fluid_edit(
                "[fluid]",
                "[fluid.pressure]\nouter_tolerance = -1.0\n\n[fluid]",
            ),
            "fluid.pressure.outer_tolerance",
            "> 0",
        ),
        (
            fluid_edit(
                "[fluid]",
                "[fluid.pressure]\nmax_outer_iterations = 0\n\n[fluid]",
            ),
            "fluid.pressure.max_outer_iterations",
            "≥ 1",
        ),
        (
            fluid_edit(
                "[fluid]",
                "[fluid.pressure]\nconvective_predictor = 1.5\n\n[fluid]",
            ),
            "fluid.pressure.convective_predictor",
            "[0, 1]",
        ),
        (
            fluid_edit("[fluid]", "[fluid]\nisothermal_fraction = 1.0"),
            "fluid.isothermal_fraction",
            "[0, 1)",
        ),
    ];
    assert_each_names_its_key(cases);
}

/// A coupled scene (steel block in air) and its bad inputs.
const COUPLED_EXTRA: &str = r#"
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

#[test]
fn coupled_scene_bad_inputs_name_their_keys() {
    let good = format!("{GOOD}{COUPLED_EXTRA}");
    mpmice::scene::parse(&good).expect("the coupled scene is valid");
    let heat = |material: &str, geometry: &str| {
        format!(
            "{good}\n[[heat_sources]]\nmaterial = \"{material}\"\ngeometry = {geometry}\npower = 1e9\nend = 1e-3\n"
        )
    };
    let disk = "{ type = \"disk\", center = [0.5, 0.5], radius = 0.1 }";
    let far = "{ type = \"disk\", center = [5.0, 5.0], radius = 0.1 }";
    let cases: Vec<(String, &str, &str)> = vec![
        (heat("water", disk), "heat_sources[0].material", "not a fluid"),
        (heat("steel", disk), "heat_sources[0].material", "not a fluid"),
        (heat("air", far), "heat_sources[0].geometry", "outside the domain"),
        // A solid-only scene has nothing to heat (a fluid-only one may).
        (
            format!(
                "{GOOD}\n[[heat_sources]]\nmaterial = \"steel\"\ngeometry = {disk}\npower = 1e9\nend = 1e-3\n"
            ),
            "heat_sources",
            "this scene has none",
        ),
        (
            format!("{good}\n[coupling]\nmomentum_exchange = -1.0\n"),
            "coupling.momentum_exchange",
            ">= 0",
        ),
        (
            format!("{good}\n[coupling]\nheat_exchange = -1.0\n"),
            "coupling.heat_exchange",
            ">= 0",
        ),
        (
            format!("{good}\n[coupling]\nheat_exchange = 1e3\n"),
            "materials[0].cv",
            "cv > 0",
        ),
        (
            GOOD.replace("poisson_ratio = 0.3", "poisson_ratio = 0.3\ncv = -450.0"),
            "materials[0].cv",
            "> 0",
        ),
        (
            format!("{good}\n[coupling]\nrigid_ramp = -0.1\n"),
            "coupling.rigid_ramp",
            ">= 0",
        ),
        (
            format!("{good}\n[coupling]\nreference_pressure = 0.0\n"),
            "coupling.reference_pressure",
            "> 0",
        ),
        (
            format!("{good}\n[coupling]\nsolid_trace_fraction = 1.0\n"),
            "coupling.solid_trace_fraction",
            "[0, 1)",
        ),
        (
            format!("{good}\n[implicit]\nhold_solid_faces = true\n"),
            "implicit.hold_solid_faces",
            "time.mode = implicit",
        ),
        (
            format!("{good}\n[coupling]\nrigid_interface = \"exact\"\n"),
            "coupling.rigid_interface",
            "`smeared` or `sharp`",
        ),
        (
            format!("{good}\n[coupling]\nrigid_interface = \"sharp\"\n")
                .replacen("cfl = 0.5", "cfl = 0.5\nmode = \"semi_implicit\"", 1),
            "coupling.rigid_interface",
            "time.mode = explicit only",
        ),
        (
            good.replace("[time]", "[mpm]\nupdate = \"musl\"\n\n[time]"),
            "mpm.update",
            "usf, usl",
        ),
        (
            format!(
                "{good}\n[[materials]]\nname = \"brass\"\ntype = \"solid\"\nmodel = \"neo_hookean\"\ndensity = 8500.0\nbulk_modulus = 1e11\nshear_modulus = 4e10\n"
            ),
            "materials[2]",
            "used by no object",
        ),
        (
            GOOD.replace("poisson_ratio = 0.3", "poisson_ratio = 0.3\nrigid = true"),
            "materials[0].rigid",
            "need a fluid",
        ),
    ];
    assert_each_names_its_key(&cases);
    // A heat exchange with the solid's c_v: built into the run, every
    // particle at the initial temperature.
    let hot = format!("{good}\n[coupling]\nheat_exchange = 1e6\nsolid_temperature = 350.0\n")
        .replace("poisson_ratio = 0.3", "poisson_ratio = 0.3\ncv = 460.0");
    let scene = mpmice::scene::parse(&hot).expect("the heated scene is valid");
    let run = mpmice::scene::build_coupled_run::<2>(&scene).expect("build");
    use mpmice::material::eos::EquationOfState;
    assert_eq!(run.coupling.heat_exchange, 1e6);
    assert_eq!(run.fields[0].eos.specific_heat_cv(), 460.0);
    assert!(!run.fields[0].particles.is_empty());
    assert!(run.fields[0]
        .particles
        .temperature
        .iter()
        .all(|&t| t == 350.0));
}

/// Two solid materials in a coupled scene: accepted, and built as two solid
/// fields (ICE materials after the fluid, named after the materials, the
/// rigid one with its objects' velocity), each with the particles of its
/// own objects — together exactly the particles of the scene.
#[test]
fn coupled_scene_with_two_solid_materials_builds_two_fields() {
    let two = format!(
        "{GOOD}{COUPLED_EXTRA}\n[[materials]]\nname = \"brass\"\ntype = \"solid\"\n\
         model = \"neo_hookean\"\nrigid = true\ndensity = 8500.0\nbulk_modulus = 1e11\n\
         shear_modulus = 4e10\n\n[[objects]]\nmaterial = \"brass\"\n\
         geometry = {{ type = \"box\", lower = [0.0, 0.9], upper = [0.3, 1.0] }}\n\
         velocity = [0.0, -2.0]\n"
    )
    .replace("upper = [0.8, 0.8]", "upper = [0.8, 0.6]");
    let scene = mpmice::scene::parse(&two).expect("two solid materials are accepted");
    let solid = mpmice::scene::build_solid_run::<2>(&scene).expect("solid build");
    let run = mpmice::scene::build_coupled_run::<2>(&scene).expect("coupled build");
    assert_eq!(run.fields.len(), 2);
    assert_eq!(run.num_fluids(), 1);
    let names: Vec<&str> = run
        .fluid
        .materials
        .iter()
        .map(|m| m.name.as_str())
        .collect();
    assert_eq!(names, ["air", "steel", "brass"]);
    assert_eq!(
        run.ice.frames,
        [
            mpmice::ice::Frame::Eulerian,
            mpmice::ice::Frame::Particles,
            mpmice::ice::Frame::Rigid
        ]
    );
    assert_eq!(run.fields[0].rigid_velocity, None);
    assert_eq!(
        run.fields[1].rigid_velocity,
        Some(nalgebra::SVector::<f64, 2>::new(0.0, -2.0))
    );
    for (k, f) in run.fields.iter().enumerate() {
        assert_eq!(f.ice_material, 1 + k);
        assert!(!f.particles.is_empty());
        assert!(f.particles.material.iter().all(|&m| m as usize == k));
    }
    let (n0, n1) = (run.fields[0].particles.len(), run.fields[1].particles.len());
    assert_eq!(n0 + n1, solid.particles.len());
    // 6 × 4 cells of steel and 3 × 1 of brass, 2 × 2 particles per cell.
    assert_eq!((n0, n1), (96, 12));
    // Every pair with a solid field exchanges at K (solid–solid too).
    let k = run.ice.exchange.as_ref().unwrap().momentum.clone();
    assert_eq!(k, [0.0, 1e15, 1e15, 1e15, 0.0, 1e15, 1e15, 1e15, 0.0]);
}

/// A coupled run needs a solid material: building one from a scene
/// without (a fluid scene) is rejected naming `materials`.
#[test]
fn coupled_run_without_a_solid_material_names_materials() {
    let scene = mpmice::scene::parse(FLUID).expect("the fluid scene is valid");
    let e = mpmice::scene::build_coupled_run::<1>(&scene)
        .err()
        .expect("no solid material: rejected");
    assert_eq!(e.path, "materials", "{e}");
    assert!(e.message.contains("at least one solid"), "{e}");
}

/// The fluid scene with an inflow face on x = 0 (air entering at 10 m/s).
fn inflow_scene(face: &str, state: &str) -> String {
    fluid_edit("x_lower = \"fixed\"", "x_lower = \"free\"").replacen(
        "exchange = { momentum = 1e15 }\n",
        &format!("exchange = {{ momentum = 1e15 }}\n\n[fluid.inflow.{face}]\n{state}\n"),
        1,
    )
}

const INFLOW_STATE: &str = "pressure = 1e5\nstates = [{ material = \"air\", volume_fraction = 1.0, temperature = 300.0, velocity = [10.0] }]";

#[test]
fn inflow_faces_are_built_and_bad_ones_name_their_key() {
    let good = inflow_scene("x_lower", INFLOW_STATE);
    let scene = mpmice::scene::parse(&good).expect("the inflow scene is valid");
    let (_, params) = mpmice::scene::build_fluid_run::<1>(&scene).expect("build");
    match &params.boundaries[0][0] {
        mpmice::ice::IceBoundary::Inflow(states) => {
            // air as given (ρ = p/(R T), R = c_v (γ − 1)), water at a trace.
            assert_eq!(states.len(), 2);
            let rho_air = 1e5 / (717.5 * 0.4 * 300.0);
            assert!((states[0].density / rho_air - 1.0).abs() < 1e-12);
            assert!((states[0].temperature / 300.0 - 1.0).abs() < 1e-12);
            assert_eq!(states[0].velocity[0], 10.0);
            assert!(states[1].vol_frac < 1e-9 && states[1].vol_frac > 0.0);
        }
        other => panic!("x_lower is {other:?}"),
    }
    assert_eq!(
        params.boundaries[0][1],
        mpmice::ice::IceBoundary::Wall,
        "x_upper stays a wall"
    );
    let st = |s: &str| INFLOW_STATE.replace("temperature = 300.0", s);
    let cases: Vec<(String, &str, &str)> = vec![
        (
            inflow_scene("x_lower", INFLOW_STATE)
                .replace("x_lower = \"free\"", "x_lower = \"fixed\""),
            "fluid.inflow.x_lower",
            "grid.boundary.x_lower = \"free\"",
        ),
        (
            inflow_scene("y_lower", INFLOW_STATE),
            "fluid.inflow.y_lower",
            "allowed faces: x_lower, x_upper",
        ),
        (
            inflow_scene("x_min", INFLOW_STATE),
            "fluid.inflow.x_min",
            "x_lower",
        ),
        (
            inflow_scene("x_lower", &INFLOW_STATE.replace("\"air\"", "\"oil\"")),
            "fluid.inflow.x_lower.states[0].material",
            "unknown fluid material `oil`; defined: air, water",
        ),
        (
            inflow_scene("x_lower", &st("temperature = -300.0")),
            "fluid.inflow.x_lower.states[0].temperature",
            "> 0",
        ),
        (
            inflow_scene("x_lower", &st("temperature = 300.0, density = 1.0")),
            "fluid.inflow.x_lower.states[0].density",
            "exactly one of density or temperature",
        ),
        (
            inflow_scene("x_lower", &INFLOW_STATE.replace("1.0,", "0.5,")),
            "fluid.inflow.x_lower.states",
            "sum to 1",
        ),
        (
            inflow_scene("x_lower", &INFLOW_STATE.replace("[10.0]", "[10.0, 0.0]")),
            "fluid.inflow.x_lower.states[0].velocity",
            "1 components",
        ),
        (
            inflow_scene(
                "x_lower",
                &INFLOW_STATE.replace("pressure = 1e5", "pressure = -1e5"),
            ),
            "fluid.inflow.x_lower.pressure",
            "> 0",
        ),
        (
            inflow_scene("x_lower", &INFLOW_STATE.replace("pressure = 1e5\n", "")),
            "fluid.inflow.x_lower",
            "missing field `pressure`",
        ),
        (
            inflow_scene("x_lower", &format!("{INFLOW_STATE}\nspeed = 3.0")),
            "fluid.inflow.x_lower.speed",
            "pressure",
        ),
        (
            format!("{GOOD}{COUPLED_EXTRA}\n[fluid.inflow.x_upper]\n{INFLOW_STATE}\n")
                .replace("[10.0]", "[10.0, 0.0]"),
            "fluid.inflow.x_upper",
            "fluid-only",
        ),
        (
            format!("{GOOD}\n[fluid.inflow.x_upper]\n{INFLOW_STATE}\n"),
            "fluid.inflow",
            "no fluid",
        ),
    ];
    assert_each_names_its_key(&cases);
}

/// `grid.axisymmetric`: the good scene on the axis (x_lower = symmetry) is
/// accepted; every misuse names its key.
#[test]
fn axisymmetric_bad_inputs_name_their_keys() {
    let axi = |s: &str| {
        s.replacen("dim = 2", "dim = 2\naxisymmetric = true", 1)
            .replacen("x_lower = \"fixed\"", "x_lower = \"symmetry\"", 1)
    };
    let good = axi(GOOD);
    let scene = mpmice::scene::parse(&good).expect("the axisymmetric scene is valid");
    let run = mpmice::scene::build_solid_run::<2>(&scene).expect("builds");
    assert!(run.grid.axisymmetric);
    let three_d = good
        .replacen("dim = 2", "dim = 3", 1)
        .replacen("lower = [0.0, 0.0]", "lower = [0.0, 0.0, 0.0]", 1)
        .replacen("upper = [1.0, 1.0]", "upper = [1.0, 1.0, 1.0]", 1)
        .replacen("cells = [10, 10]", "cells = [10, 10, 10]", 1)
        .replacen("lower = [0.2, 0.2]", "lower = [0.2, 0.2, 0.2]", 1)
        .replacen("upper = [0.8, 0.8]", "upper = [0.8, 0.8, 0.8]", 1)
        .replacen("velocity = [1.0, 0.0]", "velocity = [1.0, 0.0, 0.0]", 1);
    let cases: Vec<(String, &str, &str)> = vec![
        (
            edit("dim = 2", "dim = 2\naxisymmetric = true"),
            "grid.boundary.x_lower",
            "symmetry",
        ),
        (
            good.replacen("lower = [0.0, 0.0]", "lower = [-0.5, 0.0]", 1),
            "grid.lower",
            "≥ 0",
        ),
        (three_d, "grid.axisymmetric", "grid.dim = 2"),
        (
            good.replacen("cfl = 0.5", "cfl = 0.5\nmode = \"implicit\"\ndt = 0.01", 1),
            "grid.axisymmetric",
            "explicit",
        ),
        (format!("{good}{COUPLED_EXTRA}"), "grid.axisymmetric", "ICE"),
    ];
    assert_each_names_its_key(&cases);
    // Off the axis (lower r > 0) any face condition is allowed.
    let off_axis = edit("dim = 2", "dim = 2\naxisymmetric = true").replacen(
        "lower = [0.0, 0.0]",
        "lower = [0.1, 0.0]",
        1,
    );
    mpmice::scene::parse(&off_axis).expect("an axisymmetric grid off the axis is valid");
}

/// A membrane (York Sec. 3.2) around gas points: the good scene of the
/// membrane checks below.
const MEMBRANE: &str = r#"
[grid]
dim = 2
lower = [0.0, 0.0]
upper = [1.0, 1.0]
cells = [10, 10]
boundary = { x_lower = "fixed", x_upper = "fixed", y_lower = "fixed", y_upper = "fixed" }

[time]
end = 0.01

[[materials]]
name = "gas"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 1.0

[[materials]]
name = "skin"
type = "membrane"
density = 0.5
youngs_modulus = 1.0e4
poisson_ratio = 0.3
thickness = 0.1

[[objects]]
material = "skin"
geometry = { type = "polyline", vertices = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]], closed = true }
spacing = 0.05

[[objects]]
material = "gas"
geometry = { type = "circle", center = [0.5, 0.5], radius = 0.25 }
density = 1.0
pressure = 1.0
"#;

fn membrane_edit(from: &str, to: &str) -> String {
    assert_eq!(MEMBRANE.matches(from).count(), 1, "edit anchor `{from}`");
    MEMBRANE.replacen(from, to, 1)
}

#[test]
fn the_membrane_scene_is_accepted_and_builds_ordered_points() {
    let s = mpmice::scene::parse(MEMBRANE).expect("valid");
    let run = mpmice::scene::build_solid_run::<2>(&s).expect("builds");
    let c = run.membranes.chains[0];
    // Perimeter 2.4 at spacing 0.05: 48 points, closed, each of mass
    // ρ h Δ = 0.5 · 0.1 · 0.05.
    assert_eq!((c.first, c.count, c.closed), (0, 48, true));
    for p in 0..48 {
        assert!((run.particles.mass[p] - 0.0025).abs() < 1e-15);
    }
}

#[test]
fn bad_membrane_input_names_its_key() {
    let square = "vertices = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]], closed = true";
    let cases: Vec<(String, &str, &str)> = vec![
        (
            membrane_edit(square, "vertices = [[0.2, 0.2], [0.8, 0.8], [0.8, 0.2], [0.2, 0.8]], closed = true"),
            "objects[0].geometry.vertices",
            "crosses",
        ),
        (
            membrane_edit(square, "vertices = [[0.2, 0.2], [0.8, 0.2], [0.5, 0.2]]"),
            "objects[0].geometry.vertices",
            "in order",
        ),
        (
            membrane_edit(square, "vertices = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.2], [0.2, 0.8]], closed = true"),
            "objects[0].geometry.vertices[2]",
            "zero-length",
        ),
        (
            membrane_edit(square, "vertices = [[0.2, 0.2]]"),
            "objects[0].geometry.vertices",
            "at least 2",
        ),
        (
            membrane_edit("spacing = 0.05", "spacing = 0.2"),
            "objects[0].spacing",
            "smallest cell size",
        ),
        (
            membrane_edit("spacing = 0.05\n", ""),
            "objects[0].spacing",
            "missing",
        ),
        (
            membrane_edit("spacing = 0.05", "spacing = 0.05\nfixed_ends = true"),
            "objects[0].fixed_ends",
            "open polylines",
        ),
        (
            membrane_edit("thickness = 0.1", "thickness = 0.0"),
            "materials[1].thickness",
            "> 0",
        ),
        (
            membrane_edit("thickness = 0.1\n", ""),
            "materials[1].thickness",
            "missing",
        ),
        (
            membrane_edit("poisson_ratio = 0.3", "poisson_ratio = 0.3\nmodel = \"neo_hookean\""),
            "materials[1].model",
            "not a membrane key",
        ),
        (
            membrane_edit("spacing = 0.05", "spacing = 0.05\nparticles_per_cell = 2"),
            "objects[0].particles_per_cell",
            "not a membrane object key",
        ),
        (
            membrane_edit("density = 1.0\npressure", "spacing = 0.05\ndensity = 1.0\npressure"),
            "objects[1].spacing",
            "only for membrane objects",
        ),
        (
            membrane_edit(
                "{ type = \"polyline\", vertices = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]], closed = true }",
                "{ type = \"box\", lower = [0.2, 0.2], upper = [0.8, 0.8] }",
            ),
            "objects[0].geometry.type",
            "polyline, circle, dog_bone",
        ),
        (
            membrane_edit(
                "{ type = \"circle\", center = [0.5, 0.5], radius = 0.25 }",
                "{ type = \"dog_bone\", center = [0.5, 0.5], lobe_radius = 0.1, lobe_offset = 0.3, neck_half_width = 0.2 }",
            ),
            "objects[1].geometry.neck_half_width",
            "lobe_radius",
        ),
        (
            membrane_edit("end = 0.01", "end = 0.01\nmode = \"implicit\"\ndt = 0.001"),
            "time.mode",
            "explicit",
        ),
        (
            membrane_edit("frame = \"particles\"\n", ""),
            "materials[0].frame",
            "ICE",
        ),
        (
            membrane_edit("thickness = 0.1", "thickness = 0.1\n[[materials]]\nname = \"air\"\ntype = \"fluid\"\neos = \"ideal_gas\"\ngamma = 1.4\ncv = 1.0"),
            "materials[2].frame",
            "ICE",
        ),
        (
            membrane_edit("dim = 2\nlower = [0.0, 0.0]\nupper = [1.0, 1.0]\ncells = [10, 10]", "dim = 3\nlower = [0.0, 0.0, 0.0]\nupper = [1.0, 1.0, 1.0]\ncells = [10, 10, 10]"),
            "grid.dim",
            "2D only",
        ),
    ];
    assert_each_names_its_key(&cases);
}

/// Membranes of revolution (York Sec. 3.2 in r–z): the membrane scene made
/// axisymmetric is accepted, and so is a surface closed at the axis (an
/// open polyline from the axis to the axis, whose end points sit half an
/// interval off it); a curve reaching r < 0, a closed curve touching the
/// axis and a circle crossing it are rejected naming the key.
#[test]
fn axisymmetric_membranes_stay_off_the_axis_naming_the_key() {
    let axi = |s: String| {
        s.replacen("dim = 2", "dim = 2\naxisymmetric = true", 1)
            .replacen("x_lower = \"fixed\"", "x_lower = \"symmetry\"", 1)
    };
    let good = axi(MEMBRANE.to_string());
    let run = mpmice::scene::build_solid_run::<2>(&mpmice::scene::parse(&good).expect("valid"))
        .expect("builds");
    // Per radian: mass ρ h Δ r of each point.
    for p in 0..48 {
        let r = run.particles.x[p][0];
        assert!((run.particles.mass[p] - 0.0025 * r).abs() < 1e-15);
    }
    let square = "vertices = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]], closed = true";
    let pole = axi(membrane_edit(
        square,
        "vertices = [[0.0, 0.2], [0.6, 0.2], [0.6, 0.8], [0.0, 0.8]]",
    ));
    let run = mpmice::scene::build_solid_run::<2>(&mpmice::scene::parse(&pole).expect("valid"))
        .expect("builds");
    let c = run.membranes.chains[0];
    // Length 1.8 at spacing 0.05: 36 points at the middles of 36 intervals.
    assert_eq!((c.count, c.closed), (36, false));
    assert!((run.particles.x[0][0] - 0.025).abs() < 1e-12);
    assert!((run.particles.x[35][0] - 0.025).abs() < 1e-12);
    let cases: Vec<(String, &str, &str)> = vec![
        (
            axi(membrane_edit(
                square,
                "vertices = [[-0.1, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]], closed = true",
            )),
            "objects[0].geometry.vertices[0]",
            "x ≥ 0",
        ),
        (
            axi(membrane_edit(
                square,
                "vertices = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [-0.2, 0.8]]",
            )),
            "objects[0].geometry.vertices[3]",
            "x ≥ 0",
        ),
        (
            axi(membrane_edit(
                square,
                "vertices = [[0.0, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]], closed = true",
            )),
            "objects[0].geometry.vertices[0]",
            "x > 0 on a closed one",
        ),
        (
            axi(membrane_edit(
                "{ type = \"polyline\", vertices = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]], closed = true }",
                "{ type = \"circle\", center = [0.2, 0.5], radius = 0.25 }",
            )),
            "objects[0].geometry.center",
            "radius",
        ),
    ];
    assert_each_names_its_key(&cases);
}

/// The Mie–Grüneisen water of `cases/mie_gruneisen_shock.toml` and a JWL
/// products scene: unphysical parameters are rejected with the key named.
const MG_CASE: &str = include_str!("../cases/mie_gruneisen_shock.toml");

const JWL: &str = r#"
[grid]
dim = 1
lower = [0.0]
upper = [1.0]
cells = [20]
boundary = { x_lower = "fixed", x_upper = "fixed" }

[time]
end = 1e-6

[[materials]]
name = "products"
type = "fluid"
eos = "jwl"
a = 371.2e9
b = 3.231e9
r1 = 4.15
r2 = 0.95
omega = 0.3
reference_density = 1630.0
cv = 1000.0

[[regions]]
pressure = 1e9
states = [{ material = "products", volume_fraction = 1.0, temperature = 3000.0 }]
"#;

fn mg_edit(from: &str, to: &str) -> String {
    assert_eq!(MG_CASE.matches(from).count(), 1, "edit anchor `{from}`");
    MG_CASE.replacen(from, to, 1)
}

fn jwl_edit(from: &str, to: &str) -> String {
    assert_eq!(JWL.matches(from).count(), 1, "edit anchor `{from}`");
    JWL.replacen(from, to, 1)
}

#[test]
fn the_mie_gruneisen_and_jwl_scenes_are_accepted() {
    mpmice::scene::parse(MG_CASE).expect("Mie–Grüneisen case");
    let s = mpmice::scene::parse(JWL).expect("JWL scene");
    let (st, _) = mpmice::scene::build_fluid_run::<1>(&s).expect("JWL builds");
    assert!((st.p_eq[st.layout.interior[0]] / 1e9 - 1.0).abs() < 1e-12);
}

#[test]
fn bad_mie_gruneisen_and_jwl_input_names_its_key() {
    let cases: &[(String, &str, &str)] = &[
        (
            mg_edit("gruneisen = 0.5", "gruneisen = -0.1"),
            "materials[0].gruneisen",
            ">= 0",
        ),
        (
            mg_edit("gruneisen = 0.5", "gruneisen = 4.0"),
            "materials[0].gruneisen",
            "< 2 s",
        ),
        (mg_edit("c0 = 1483.0", "c0 = 0.0"), "materials[0].c0", "> 0"),
        (
            mg_edit("c0 = 1483.0", "c0 = -5.0"),
            "materials[0].c0",
            "> 0",
        ),
        (
            mg_edit("\ns = 1.75\n", "\ns = -1.0\n"),
            "materials[0].s",
            "[1, 4]",
        ),
        (
            mg_edit("\ns = 1.75\n", "\ns = 6.0\n"),
            "materials[0].s",
            "singular",
        ),
        (
            mg_edit("reference_density = 998.0", "reference_density = 0.0"),
            "materials[0].reference_density",
            "> 0",
        ),
        (
            mg_edit("reference_density = 998.0", "reference_density = -998.0"),
            "materials[0].reference_density",
            "> 0",
        ),
        (
            mg_edit(
                "reference_temperature = 293.0",
                "reference_temperature = 0.0",
            ),
            "materials[0].reference_temperature",
            "> 0",
        ),
        (
            mg_edit("cv = 4180.0", "cv = 1e6"),
            "materials[0].cv",
            "tension",
        ),
        (mg_edit("c0 = 1483.0\n", ""), "materials[0].c0", "missing"),
        (
            mg_edit("cv = 4180.0", "cv = 4180.0\ngamma = 1.4"),
            "materials[0].gamma",
            "not read by eos = \"mie_gruneisen\"",
        ),
        (
            mg_edit("cv = 4180.0", "cv = 4180.0\nomega = 0.3"),
            "materials[0].omega",
            "reference_pressure",
        ),
        (
            // Below the hyperbolic limit (p0 − K)/(1 + Γ0) ≈ −1.46 GPa.
            mg_edit("\npressure = 101325.0", "\npressure = -2e9"),
            "regions[0].pressure",
            "must be >",
        ),
        (
            // ω > R1, R2: p(ρ0, T0) < 0 at the reference state.
            jwl_edit("omega = 0.3", "omega = 5.0\nreference_temperature = 1.0"),
            "materials[0].a",
            "positive pressure",
        ),
        (jwl_edit("r1 = 4.15", "r1 = 0.0"), "materials[0].r1", "> 0"),
        (jwl_edit("r2 = 0.95", "r2 = -1.0"), "materials[0].r2", "> 0"),
        (
            jwl_edit("omega = 0.3", "omega = 0.0"),
            "materials[0].omega",
            "> 0",
        ),
        (
            jwl_edit("reference_density = 1630.0", "reference_density = 0.0"),
            "materials[0].reference_density",
            "> 0",
        ),
        (jwl_edit("a = 371.2e9\n", ""), "materials[0].a", "missing"),
        (
            jwl_edit("omega = 0.3", "omega = 0.3\ns = 1.5"),
            "materials[0].s",
            "not read by eos = \"jwl\"",
        ),
        (
            jwl_edit("pressure = 1e9", "pressure = -1e5"),
            "regions[0].pressure",
            "must be > 0",
        ),
        (
            mg_edit(
                "type = \"fluid\"\neos = \"mie_gruneisen\"",
                "type = \"fluid\"\neos = \"mie_gruneisen\"\np_inf = 1e8",
            ),
            "materials[0].p_inf",
            "not read",
        ),
        (
            // Γ0 = 0: p(ρ) only, so a region cannot give the density.
            mg_edit("gruneisen = 0.5", "gruneisen = 0.0")
                .replace("temperature = 293.0, velocity", "density = 998.0, velocity"),
            "regions[0].states[0].density",
            "give temperature",
        ),
        (
            mg_edit(
                "type = \"fluid\"",
                "type = \"fluid\"\nframe = \"particles\"",
            )
            .replace("gruneisen = 0.5", "gruneisen = 0.0"),
            "materials[0].gruneisen",
            "gas points",
        ),
        (
            edit(
                "model = \"linear_elastic\"",
                "model = \"linear_elastic\"\ngruneisen = 2.0",
            ),
            "materials[0].gruneisen",
            "only for fluid",
        ),
    ];
    assert_each_names_its_key(cases);
}

/// Settings the scene's mode ignores are rejected, naming the key and the
/// mode (or materials) that would read them.
#[test]
fn settings_the_mode_ignores_are_rejected() {
    const AIR: &str = "[[materials]]\nname = \"air\"";
    let fluid_table = "[fluid]\nexchange = { momentum = 1e15 }\n";
    let cases: Vec<(String, &str, &str)> = vec![
        (
            fluid_edit(
                AIR,
                &format!("[coupling]\nmomentum_exchange = 1e15\n\n{AIR}"),
            ),
            "coupling",
            "coupled scenes",
        ),
        (
            edit(
                "[[materials]]",
                "[coupling]\nmomentum_exchange = 1e15\n\n[[materials]]",
            ),
            "coupling",
            "coupled scenes",
        ),
        (
            edit(
                "[[materials]]",
                "[implicit]\nmax_newton_iterations = 5\n\n[[materials]]",
            ),
            "implicit",
            "time.mode = \"explicit\"",
        ),
        (
            fluid_edit(
                AIR,
                &format!("[fluid.pressure]\nsolver = \"direct\"\n\n{AIR}"),
            ),
            "fluid.pressure",
            "semi_implicit",
        ),
        (
            fluid_edit(
                fluid_table,
                "[fluid]\nexchange = { momentum = 1e15 }\npressure = { solver = \"direct\" }\n",
            ),
            "fluid.pressure",
            "time.mode = \"explicit\"",
        ),
        (
            fluid_edit("cv = 717.5\n", "cv = 717.5\nrigid = true\n"),
            "materials[0].rigid",
            "only for solid materials",
        ),
        (
            edit(
                "[[materials]]",
                "[fluid]\nvariant = \"literal\"\n\n[[materials]]",
            ),
            "fluid",
            "fluid materials in the cells",
        ),
        (
            fluid_edit(AIR, &format!("[mpm]\nparticles_per_cell = 3\n\n{AIR}")),
            "mpm",
            "particles",
        ),
    ];
    assert_each_names_its_key(&cases);
}
