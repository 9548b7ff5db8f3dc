//! The same scene gives bit-identical results with 1 and 2 threads (the
//! particle-to-grid scatter is slab-coloured, see `mpm::scatter`).

use mpmice::driver::{run_scene, RunOptions};

fn scene(shape: &str) -> mpmice::scene::Scene {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/two_disks.toml"))
            .expect("default scene");
    let mut s = mpmice::scene::parse(&text).expect("valid");
    // Through the collision (t ≈ 1.25) at a coarser grid, quickly.
    s.time.end = 1.6;
    s.grid.cells = vec![32, 32];
    s.mpm.shape = serde_json::from_str(&format!("\"{shape}\"")).expect("shape");
    s.output.interval = None;
    s
}

#[test]
fn one_and_two_threads_are_bit_identical() {
    let dir = tempfile::tempdir().expect("tmp");
    for shape in mpmice::shape::ShapeKind::ALL.map(|s| s.name()) {
        let s = scene(shape);
        let mut outputs = Vec::new();
        for threads in [1usize, 2] {
            let out = dir.path().join(format!("{shape}_{threads}"));
            let opts = RunOptions::quiet(out.clone(), threads);
            let sum = run_scene(&s, &opts).expect("run");
            assert_eq!(sum.threads, threads);
            assert!(sum.steps > 50);
            outputs.push((
                std::fs::read(out.join("particles_0001.csv")).expect("final snapshot"),
                std::fs::read(out.join("history.csv")).expect("history"),
                std::fs::read(out.join("particles_0001.vtu")).expect("vtu"),
            ));
        }
        assert!(
            outputs[0] == outputs[1],
            "{shape}: 1- and 2-thread outputs differ"
        );
    }
}

/// A 1D ICE grid longer than one piece of `ice::par` (4096 cells) is cut
/// into pieces shared by the threads; the cells must come out the same to
/// the bit with 1 and 2 threads, explicit and semi-implicit.
#[test]
fn long_1d_ice_rows_are_bit_identical_across_threads() {
    let dir = tempfile::tempdir().expect("tmp");
    for case in ["sod", "sod_semi_implicit"] {
        let path = format!("{}/cases/{case}.toml", env!("CARGO_MANIFEST_DIR"));
        let mut s = mpmice::scene::load(std::path::Path::new(&path)).expect("case");
        // Three whole pieces and a part one (the waves start at x = 0.5,
        // inside the second piece).
        s.grid.cells = vec![3 * 4096 + 1000];
        s.time.max_steps = Some(40);
        s.output.interval = None;
        let mut outputs = Vec::new();
        for threads in [1usize, 2] {
            let out = dir.path().join(format!("{case}_{threads}"));
            let sum = run_scene(&s, &RunOptions::quiet(out.clone(), threads)).expect("run");
            assert_eq!(sum.steps, 40);
            outputs.push((
                std::fs::read(out.join("cells_0001.csv")).expect("final cells"),
                std::fs::read(out.join("history.csv")).expect("history"),
            ));
        }
        assert!(
            outputs[0] == outputs[1],
            "{case}: 1- and 2-thread outputs differ"
        );
    }
}

/// The 3D benchmark block (52³ particles on 32³ cells: nine slabs, so the
/// odd slabs start as soon as their even neighbours finish) gives the same
/// particles to the bit on 1 and 2 threads.
#[test]
fn the_3d_block_is_bit_identical_across_threads() {
    use mpmice::diagnostics::bench_cases::rotating_block_3d;
    use mpmice::shape::ShapeKind;
    let mut states = Vec::new();
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let mut run = rotating_block_3d(ShapeKind::QuadraticBspline);
        pool.install(|| {
            for _ in 0..4 {
                run.step().expect("step");
            }
        });
        let p = &run.particles;
        let bits: Vec<u64> =
            p.x.iter()
                .chain(&p.v)
                .flat_map(|v| v.iter().map(|c| c.to_bits()).collect::<Vec<_>>())
                .chain(
                    p.stress
                        .iter()
                        .flat_map(|s| s.iter().map(|c| c.to_bits()).collect::<Vec<_>>()),
                )
                .collect();
        states.push(bits);
    }
    assert!(states[0] == states[1], "1- and 2-thread 3D blocks differ");
}
