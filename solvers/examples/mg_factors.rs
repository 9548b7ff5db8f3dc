//! Multigrid convergence study: stationary convergence factor (geometric
//! mean of successive residual ratios, zero-mean random rhs, random initial
//! guess) and PCG-MG iteration counts to 1e-10 for several cycle variants
//! on Poisson and 1e3-jump problems.
//!
//! Usage: `cargo run --release -p solvers --example mg_factors [-- FILTER]`

#[path = "../tests/common/mod.rs"]
mod common;

use common::*;
use solvers::*;

fn main() {
    let filt = std::env::args().nth(1).unwrap_or_default();
    let d2 = [256, 256, 1];
    let d3 = [32, 32, 32];
    let d3b = [64, 64, 64];
    let cases: Vec<(&str, CellStencil)> = vec![
        (
            "2D Poisson Dirichlet 256^2",
            poisson(d2, BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "2D Poisson Neumann+1e-6 256^2",
            poisson(d2, BoundaryKind::Neumann, 1e-6),
        ),
        (
            "2D Poisson Dirichlet 255^2",
            poisson([255, 255, 1], BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "2D inclusion 1e3 256^2",
            from_field(d2, &inclusion_field(d2, 1e3), BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "2D inclusion 1e-3 Neu 256^2",
            from_field(d2, &inclusion_field(d2, 1e-3), BoundaryKind::Neumann, 1e-6),
        ),
        (
            "2D checkerboard 1e3 256^2",
            from_field(
                d2,
                &checkerboard_field(d2, 8, 1e3),
                BoundaryKind::Dirichlet,
                0.0,
            ),
        ),
        (
            "3D Poisson Dirichlet 32^3",
            poisson(d3, BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "3D Poisson Neumann+1e-6 32^3",
            poisson(d3, BoundaryKind::Neumann, 1e-6),
        ),
        (
            "3D Poisson Dirichlet 64^3",
            poisson(d3b, BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "3D Poisson Dirichlet 33^3",
            poisson([33, 33, 33], BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "3D inclusion 1e3 32^3",
            from_field(d3, &inclusion_field(d3, 1e3), BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "3D checkerboard 1e3 64^3",
            from_field(
                d3b,
                &checkerboard_field(d3b, 4, 1e3),
                BoundaryKind::Dirichlet,
                0.0,
            ),
        ),
    ];
    let base = MgOptions::default();
    let variants = [
        ("linear V(3,3) [default]", base),
        (
            "linear V(2,2)",
            MgOptions {
                pre_smooth: 2,
                post_smooth: 2,
                ..base
            },
        ),
        (
            "linear V(1,1)",
            MgOptions {
                pre_smooth: 1,
                post_smooth: 1,
                ..base
            },
        ),
        (
            "linear W(2,2)",
            MgOptions {
                pre_smooth: 2,
                post_smooth: 2,
                cycle: Cycle::W,
                ..base
            },
        ),
        (
            "constant V(2,2)",
            MgOptions {
                pre_smooth: 2,
                post_smooth: 2,
                prolongation: Prolongation::Constant,
                ..base
            },
        ),
    ];
    println!(
        "{:32} {:24} {:>6} {:>8} {:>8}",
        "problem", "cycle", "levels", "factor", "pcg-its"
    );
    for (name, st) in cases.iter().filter(|c| c.0.contains(&filt)) {
        let n = st.num_cells();
        for (vn, o) in &variants {
            let mg = Multigrid::new(st, o).unwrap();
            let f = mg_factor(&mg, n, 3, 60);
            let b = zero_mean_rhs(n, 3);
            let mut x = vec![0.0; n];
            let mut ws = KrylovWorkspace::new();
            let opts = KrylovOptions {
                rel_tol: 1e-10,
                max_iter: 200,
            };
            let its = match pcg(st, &mg, &b, &mut x, &opts, &mut ws) {
                Ok(r) => r.iterations.to_string(),
                Err(e) => format!("{e}"),
            };
            let fs = if f < 1.0 {
                format!("{f:.3}")
            } else {
                format!("{f:.2} (div)")
            };
            println!("{name:32} {vn:24} {:>6} {fs:>8} {its:>8}", mg.num_levels());
        }
    }
}
