//! The resolution study's limit (`study::resolution::limit`): Richardson extrapolation against
//! sequences with a known limit and order, and the settling rule against known motions.

use springlab::study::observe::{Component, Observation, SAMPLES, Unit, Value};
use springlab::study::resolution::limit::{self, richardson};

fn length(x: f64) -> Observation {
    Observation {
        components: vec![Component {
            name: "sag".into(),
            unit: Unit::Metre,
            value: Value::Length(x),
        }],
    }
}

#[test]
fn richardson_recovers_the_order_and_limit_of_a_power_law() {
    // O(h) = O∞ + C h^p exactly, at unequal spacing ratios (the cloth's n = 17, 25, 35).
    for (limit, c, p) in [(0.5, 3.0, 2.0), (0.52, -0.9, 0.7), (1.0, 40.0, 4.0)] {
        let h = [1.0 / 16.0, 1.0 / 24.0, 1.0 / 34.0];
        let o = h.map(|h: f64| limit + c * h.powf(p));
        let e = richardson(h, o).expect("monotone");
        assert!((e.order - p).abs() < 1e-7, "order {} for {p}", e.order);
        assert!(
            (e.limit - limit).abs() < 1e-10,
            "limit {} for {limit}",
            e.limit
        );
    }
}

#[test]
fn with_equal_ratios_richardson_is_the_textbook_formula() {
    // r = 2: p = log2((O1 - O2)/(O2 - O3)), O∞ = O3 + (O3 - O2)/(2^p - 1).
    let o = [0.9, 0.95, 0.97];
    let e = richardson([0.4, 0.2, 0.1], o).expect("monotone");
    let p = ((o[0] - o[1]) / (o[1] - o[2])).log2();
    assert!((e.order - p).abs() < 1e-9);
    let textbook = o[2] + (o[2] - o[1]) / (2f64.powf(p) - 1.0);
    assert!((e.limit - textbook).abs() < 1e-12);
}

#[test]
fn richardson_refuses_oscillating_or_stalled_sequences() {
    let h = [0.3, 0.2, 0.1];
    assert!(richardson(h, [1.0, 1.2, 1.1]).is_none(), "sign change");
    assert!(richardson(h, [1.0, 1.0, 1.1]).is_none(), "no change");
    assert!(richardson([0.1, 0.2, 0.3], [1.0, 1.1, 1.15]).is_none());
}

#[test]
fn the_limit_uses_the_three_finest_levels_and_the_coarser_triple_for_its_uncertainty() {
    // Second order plus a fourth-order term: the two extrapolations differ, and the finer one
    // is nearer the true limit 2.
    let levels = [9i64, 13, 17, 25, 35];
    let obs: Vec<Observation> = levels
        .iter()
        .map(|&n| {
            let h = 1.0 / (n - 1) as f64;
            length(2.0 - 5.0 * h * h + 300.0 * h.powi(4))
        })
        .collect();
    let series: Vec<(i64, f64, &Observation)> = levels
        .iter()
        .zip(&obs)
        .map(|(&n, o)| (n, 1.0 / (n - 1) as f64, o))
        .collect();
    let limits = limit::limits(&series);
    let l = limits[0].as_ref().expect("a limit");
    assert_eq!(l.levels, [17, 25, 35]);
    let previous = l.previous.expect("four levels or more");
    assert!((l.uncertainty - (l.limit - previous.limit).abs()).abs() < 1e-15);
    assert!((l.limit - 2.0).abs() < (previous.limit - 2.0).abs());
    assert!(
        (l.limit - 2.0).abs() <= l.uncertainty,
        "the uncertainty covers the truth"
    );
    // The distance of each level from the limit, |O - O∞| + u, as the study uses it.
    let (metres, seconds) = limit::distance(&obs[4], &limits);
    let expected = (obs[4].components[0].headline() - l.limit).abs() + l.uncertainty;
    assert_eq!(metres, expected);
    assert_eq!(seconds, 0.0);
}

#[test]
fn an_answer_that_still_moves_over_the_last_fifth_is_not_settled() {
    // The sag approaching 0.5 m as 0.5 - 0.1 e^(-t/τ), sampled at k T/20: settled for a short
    // τ, not for a long one; the window starts at 0.8 T.
    let horizon = 3.0;
    let x = 0.01;
    let run = |tau: f64| -> Vec<Observation> {
        (1..=SAMPLES)
            .map(|k| {
                let t = k as f64 * horizon / SAMPLES as f64;
                length(0.5 - 0.1 * (-t / tau).exp())
            })
            .collect()
    };
    let quick = limit::settling(&run(0.2), horizon, x).expect("enough samples");
    assert!((quick.from - 2.4).abs() < 1e-12);
    assert!(quick.settled, "{quick:?}");
    let slow = limit::settling(&run(3.0), horizon, x).expect("enough samples");
    let moved = 0.1 * ((-2.4f64 / 3.0).exp() - (-1.0f64).exp());
    assert!((slow.metres - moved).abs() < 1e-12);
    assert!(!slow.settled && moved > x / 10.0);
    assert!(limit::settling(&run(3.0)[..3], horizon, x).is_none());
}
