fn main() {
    let (t, x) = mpmice::diagnostics::zhang_spall::analytic();
    println!("analytic t {t:.4e} x {x:.4e}");
    for cells in [161, 322, 644] {
        let s = mpmice::diagnostics::zhang_spall::run_spall(cells).unwrap();
        println!(
            "{cells}: t {:.4e} ({:+.4}) plane {:.4e} band {:?} steps {}",
            s.time,
            (s.time - t) / t,
            s.plane,
            s.band,
            s.steps
        );
    }
}
