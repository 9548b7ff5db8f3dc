//! Prints the axis-aligned MMS error sequence for one shape function and
//! amplitude: `cargo run --release -p probes --bin mms_probe -- gimp 0.05 1`
//! (shape, amplitude, dimension, optional Courant number, default 0.2).
use mpmice::diagnostics::mms::{run_mms, AxisAlignedMms};
use mpmice::mpm::UpdateScheme;
use mpmice::shape::ShapeKind;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let shape = match a.get(1).map(String::as_str).unwrap_or("gimp") {
        "linear" => ShapeKind::Linear,
        "bspline2" => ShapeKind::QuadraticBspline,
        "bspline3" => ShapeKind::CubicBspline,
        "bspline2_gimp" => ShapeKind::QuadraticBsplineGimp,
        _ => ShapeKind::Gimp,
    };
    let amp: f64 = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.05);
    let dim: usize = a.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let cfl: f64 = a.get(4).and_then(|s| s.parse().ok()).unwrap_or(0.2);
    let mms = AxisAlignedMms::standard(amp);
    let mut prev: Option<f64> = None;
    for n in [8, 16, 32, 64, 128, 256, 512] {
        if dim == 2 && n > 128 {
            break;
        }
        let m = if dim == 1 {
            run_mms::<1>(&mms, shape, UpdateScheme::Usl, n, cfl)
        } else {
            run_mms::<2>(&mms, shape, UpdateScheme::Usl, n, cfl)
        }
        .expect("run");
        let order = prev.map(|e| (e / m.error).log2());
        println!(
            "N = {n:4}: error {:.3e}  order {:?}",
            m.error,
            order.map(|o| (o * 100.0).round() / 100.0)
        );
        prev = Some(m.error);
    }
}
