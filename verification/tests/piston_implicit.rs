//! The adiabatic piston (Guilkey 4.2) in implicit mode at steps set by the
//! piston's motion (the quick `piston_implicit` study): the closed-end
//! pressure at V1/V2 = 5 against the adiabat `P1 5^1.4`, first order in h
//! as the explicit coupled piston, in far fewer steps.

use verification::implicit_coupled_studies::piston_implicit;

#[test]
fn implicit_piston_follows_the_adiabat_at_piston_steps() {
    let r = piston_implicit(true).expect("quick study runs");
    let by_label = |l: &str| {
        r.series
            .iter()
            .find(|s| s.label.starts_with(l))
            .unwrap_or_else(|| panic!("series {l}"))
    };
    let implicit = by_label("implicit, Δt = h/4");
    let explicit = by_label("explicit");
    for (i, e) in implicit.points.iter().zip(&explicit.points) {
        let steps = |p: &verification::harness::Point| p.extra["steps"].as_f64().unwrap();
        println!(
            "h {}: implicit {:.4e} in {} steps, explicit {:.4e} in {} steps",
            i.h,
            i.error,
            steps(i),
            e.error,
            steps(e)
        );
        // The error is the smeared piston's (spatial, first order): the
        // large step adds at most 5 % of it.
        assert!(i.error < 1.05 * e.error, "{} vs {}", i.error, e.error);
        assert!(steps(i) * 5.0 < steps(e), "{} vs {}", steps(i), steps(e));
    }
    let last = implicit.points.last().expect("points");
    assert!(last.error < 0.08, "N = 120: {}", last.error);
    assert!(
        implicit.observed_order > 0.9,
        "order {}",
        implicit.observed_order
    );
}
