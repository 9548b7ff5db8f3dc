use mpmice::diagnostics::coupled::piston;
fn main() {
    let speed = 10.0;
    let mut run = piston(120, speed).unwrap();
    let mut next = 2.0;
    loop {
        run.step(f64::INFINITY).unwrap();
        let xf = 1.0 - speed * run.fluid.time;
        let ratio = 1.0 / xf;
        if ratio >= next {
            next += 1.0;
            let l = &run.fluid.layout;
            let g = &run.fluid.cells[0];
            let (mut m, mut e, mut vsum) = (0.0, 0.0, 0.0);
            for &c in &l.interior {
                let x = l.centre(c)[0];
                if x < xf { m += g.mass[c]; e += g.mass[c] * g.temperature[c]; vsum += g.mass[c]*g.sp_vol[c]; }
            }
            let t_mean = e / m;
            let t_ex = 300.0 * ratio.powf(0.4);
            println!("ratio {ratio:.2}: gas mass below face {:.5} (init 1.1768*1.0 = 1.1768), T_mean {t_mean:.3} vs adiabatic {t_ex:.3}, gas volume {vsum:.5} vs {xf:.5}", m / 0.01, );
            if ratio > 5.5 { break; }
        }
    }
}
