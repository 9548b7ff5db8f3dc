use mpmice::scene;
fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let sc = scene::load(std::path::Path::new(&args[1]))?;
    let steps: usize = args[2].parse()?;
    let from: usize = args[3].parse()?;
    let ix: isize = args[4].parse()?;
    let iy: isize = args[5].parse()?;
    let mut run = scene::build_coupled_run::<2>(&sc)?;
    let c = run.fluid.layout.index([ix, iy]);
    for s in 0..steps {
        let dt = run.step(f64::INFINITY)?.dt;
        if s >= from {
            let a = &run.fluid.cells[0];
            let st = &run.fluid.cells[1];
            println!("{s} t={:.5e} dt={:.3e} p={:.4e} air u={:.3e},{:.3e} th={:.3e} v={:.3e} T={:.4e} m={:.3e} | steel th={:.6} u={:.3e},{:.3e} m={:.6e}",
              run.fluid.time, dt, run.fluid.pressure[c], a.velocity[c][0], a.velocity[c][1], a.vol_frac[c], a.sp_vol[c], a.temperature[c], a.mass[c], st.vol_frac[c], st.velocity[c][0], st.velocity[c][1], st.mass[c]);
        }
    }
    Ok(())
}
