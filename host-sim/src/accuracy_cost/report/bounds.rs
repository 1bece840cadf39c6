//! The kernels' bounds of the cost issue ("cost figures that predict the
//! silicon"), judged like the earlier targets on each kernel's worst input
//! and in M4F guest instructions with the estimated cycles beside; the
//! filter-only ratio to the best peer; and the growth of the modal
//! tracker's cost with its number of states.

use std::collections::BTreeMap;

use bushing_kernels::input::Input;

use super::{Lines, as_accurate, m4f, per_call, per_cell, sig};
use crate::accuracy_cost::firmware::PeerLine;
use crate::accuracy_cost::host::BY_INPUT;
use crate::accuracy_cost::{Goal, Key};

/// The tracker sizes measured for the growth: (states, name suffix).
pub(in crate::accuracy_cost) const TRACKER_SIZES: [(usize, &str); 5] = [
    (4, "1-mode-1-acc"),
    (6, "1-mode-2-acc"),
    (8, "2-modes-1-acc"),
    (12, "2-modes-2-acc"),
    (16, "2-modes-3-acc"),
];

/// Highest allowed exponent of the UKF's cost in its number of states.
const GROWTH: f64 = 2.5;

/// Our update at most this share of the best peer's filter-only cost.
const FILTER_ONLY_SHARE: f64 = 0.42;

pub(super) fn goals(lines: &mut Lines, peers: &[PeerLine]) -> Vec<Goal> {
    let mut out = vec![
        per_call(
            lines,
            "Bouc-Wen n = 2 on the polynomial backbone, per step",
            200.0,
            ("friction", "bouc-wen/n-2", 1),
        ),
        per_cell(
            lines,
            "clamp Iwan cell, bank of 16, a visited cell",
            16.0,
            ("iwan", "clamp/log", 16),
        ),
        per_call(
            lines,
            "clamp Iwan bank of 16, per call",
            300.0,
            ("iwan", "clamp/log", 16),
        ),
        per_call(
            lines,
            "Maxwell bank of 8, force only, slow-exact state, per call",
            48.0,
            ("maxwell-force", "rate-exact-ramp/plain", 8),
        ),
        per_call(
            lines,
            "Maxwell bank of 8, force only, multiplicative state, per call",
            48.0,
            ("maxwell-force", "rate-exact-ramp/multiplied", 8),
        ),
        per_call(
            lines,
            "EKF tracker update, 1 mode and 1 accelerometer (4 states)",
            240.0,
            ("tracker", "ekf/1-mode-1-acc", 4),
        ),
        per_call(
            lines,
            "EKF tracker update, 2 modes on 3 accelerometers (16 states, modes fixed at compile \
             time)",
            7000.0,
            ("tracker", "ekf/2-modes-3-acc", 16),
        ),
        per_call(
            lines,
            "UKF tracker update, 2 modes on 3 accelerometers (16 states, modes fixed at compile \
             time)",
            30000.0,
            ("tracker", "ukf/2-modes-3-acc", 16),
        ),
        per_call(
            lines,
            "6-DOF engine mount, invariant form, per step",
            1300.0,
            ("six-dof", "mount/invariant", 6),
        ),
        growth(lines, "ukf"),
    ];
    let counted: Vec<&PeerLine> = peers.iter().filter(|p| p.unit == "instructions").collect();
    out.push(filter_only(&counted));
    out
}

/// The largest exponent k of `cost ∝ n^k` between successive tracker
/// sizes of one filter.
fn growth(lines: &mut Lines, filter: &str) -> Goal {
    let mut sizes: Vec<(usize, f64)> = Vec::new();
    for (n, suffix) in TRACKER_SIZES {
        let name = format!("{filter}/{suffix}");
        if let Some(l) = m4f(lines, "tracker", &name, n) {
            sizes.push((n, l.instructions()));
        }
    }
    let what = format!(
        "{} tracker cost growth with its states (from 8 states on, two modes fixed at compile \
         time), largest exponent between successive sizes",
        filter.to_uppercase()
    );
    let exponents: Vec<f64> = sizes
        .windows(2)
        .filter_map(|w| match w {
            [(n1, c1), (n2, c2)] => Some((c2 / c1).ln() / (*n2 as f64 / *n1 as f64).ln()),
            _ => None,
        })
        .collect();
    let measured = if sizes.len() == TRACKER_SIZES.len() {
        exponents.iter().copied().reduce(f64::max)
    } else {
        None
    };
    let listed: Vec<String> = sizes
        .iter()
        .map(|(n, c)| format!("{n} states {}", sig(*c)))
        .collect();
    let note = if measured.is_some() {
        format!(
            "`family=tracker name={filter}/*`, instructions net of the call: {}; exponents {}",
            listed.join(", "),
            exponents
                .iter()
                .map(|k| format!("{k:.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    } else {
        format!(
            "not every size from the M4F firmware (have {})",
            listed.join(", ")
        )
    };
    Goal {
        what,
        limit: GROWTH,
        measured,
        cycles: None,
        note,
    }
}

/// Our cheapest as-accurate tracker against the best peer's filter-only
/// cost (the peer's update less the model functions the harness gives it;
/// ours computes its model inside its update).
fn filter_only(peers: &[&PeerLine]) -> Goal {
    let what = format!(
        "our tracker <= {FILTER_ONLY_SHARE} of the best peer's filter-only cost (instructions)"
    );
    let best = peers
        .iter()
        .filter(|p| !p.is_ours() && p.model.is_some())
        .min_by(|a, b| a.filter_only().total_cmp(&b.filter_only()));
    let ours = best.and_then(|best| {
        peers
            .iter()
            .filter(|p| p.is_ours() && as_accurate(p, best))
            .min_by(|a, b| a.cost.total_cmp(&b.cost))
    });
    let (measured, note) = match (best, ours) {
        (Some(b), Some(o)) => (
            Some(o.cost / b.filter_only()),
            format!(
                "ours `{}` {} against `{}` ({}) filter only {} (its model functions {})",
                o.name,
                sig(o.cost),
                b.name,
                b.krate,
                sig(b.filter_only()),
                sig(b.model.unwrap_or(0.0))
            ),
        ),
        (Some(b), None) => (
            None,
            format!("no tracker of ours as accurate as `{}`", b.name),
        ),
        (None, _) => (None, "no peer with its model cost measured".into()),
    };
    Goal {
        what,
        limit: FILTER_ONLY_SHARE,
        measured,
        cycles: None,
        note,
    }
}

/// The host bound on the default bushing: 20 ns per step where the
/// reference kernel takes [`REFERENCE_NS`], checked as the ratio of the
/// two in the same run.
const HOST_BUSHING_NS: f64 = 20.0;

/// ns per call of the reference kernel ([`super::host::reference_kernel`])
/// on the development machine the host bound was set on (the median of the
/// full report's runs there).
const REFERENCE_NS: f64 = 16.0;

/// The default bushing on the host, as a ratio to the reference kernel of
/// the same run, on the worst of the firmware's three inputs.
pub(in crate::accuracy_cost) fn host_goal(ns: &BTreeMap<Key, f64>, reference: Option<f64>) -> Goal {
    let timed: Vec<(&str, f64)> = Input::ALL
        .iter()
        .filter_map(|input| {
            let key = Key::new(BY_INPUT, input.name(), 7, "f32");
            ns.get(&key).map(|&t| (input.name(), t))
        })
        .collect();
    // No bound on fewer than the three inputs.
    let worst = timed
        .iter()
        .copied()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .filter(|_| timed.len() == Input::ALL.len());
    let note = match (worst, reference) {
        (Some((input, t)), Some(r)) => {
            let each: Vec<String> = timed
                .iter()
                .map(|(name, t)| format!("{name} {t:.1}"))
                .collect();
            format!(
                "{t:.1} ns a step on its worst input, {input} ({}), against the reference \
                 kernel's {r:.1} ns in the same run (Horner, degree 32, f64: \
                 `bushing_sim::accuracy_cost::host::reference_kernel`); the bound is \
                 {HOST_BUSHING_NS} ns where the reference takes {REFERENCE_NS} ns, so {:.1} ns \
                 on this machine",
                each.join(", "),
                HOST_BUSHING_NS / REFERENCE_NS * r
            )
        }
        _ => "not timed".into(),
    };
    Goal {
        what: "default 1D bushing on the host, ns a step over the reference kernel's".into(),
        limit: HOST_BUSHING_NS / REFERENCE_NS,
        measured: worst.zip(reference).map(|((_, t), r)| t / r),
        cycles: None,
        note,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accuracy_cost::firmware::{parse_kernels, parse_peers};

    fn lines(costs: &[(usize, &str, f64)]) -> Lines {
        let text: String = costs
            .iter()
            .map(|(n, name, net)| {
                format!(
                    "kernel target=m4f type=f32 family=tracker name={name} n={n} per_call={} \
                     net={net}\n",
                    net + 30.0
                )
            })
            .collect();
        Lines::new(parse_kernels("k.txt", &text).expect("kernel lines")).expect("indexed")
    }

    #[test]
    fn growth_is_the_steepest_step_between_sizes() {
        // Cost ∝ n² but for a jump of 8^k from 6 to 8 states.
        let mut costs: Vec<(usize, String, f64)> = TRACKER_SIZES
            .iter()
            .map(|(n, s)| (*n, format!("ukf/{s}"), (*n * *n) as f64))
            .collect();
        let jump = (8.0f64 / 6.0).powf(4.0) * 36.0;
        for c in costs.iter_mut().skip(2) {
            c.2 *= jump / 64.0;
        }
        let refs: Vec<(usize, &str, f64)> =
            costs.iter().map(|(n, s, c)| (*n, s.as_str(), *c)).collect();
        let g = growth(&mut lines(&refs), "ukf");
        let k = g.measured.expect("every size");
        assert!((k - 4.0).abs() < 1e-9, "{k}");
        assert!(!g.met() && g.note.contains("6 states 36"), "{}", g.note);
        // A size missing: not judged.
        let g = growth(&mut lines(refs.get(..4).unwrap_or(&[])), "ukf");
        assert!(g.measured.is_none() && g.note.contains("not every size"));
    }

    #[test]
    fn the_filter_only_share_uses_the_peer_without_its_model() {
        let text = "kalman name=p crate=peer@1 filter=ekf cost=900 unit=instructions model=250 \
                    freq_err_pct=0.02 damp_err_pts=0.01 amp_rms=0.1\n\
                    kalman name=o crate=bushing filter=ekf cost=260 unit=instructions \
                    freq_err_pct=0.02 damp_err_pts=0.01 amp_rms=0.1\n";
        let peers = parse_peers("p", text).expect("peer lines");
        let refs: Vec<&PeerLine> = peers.iter().collect();
        let g = filter_only(&refs);
        assert_eq!(g.measured, Some(260.0 / 650.0));
        assert!(g.met(), "{g:?}");
        // Without the peer's model cost there is nothing to compare.
        let g = filter_only(&refs[1..]);
        assert!(g.measured.is_none());
    }

    #[test]
    fn the_host_bound_is_a_ratio_to_the_reference_kernel_on_the_worst_input() {
        let key = |input: &str| Key::new(BY_INPUT, input, 7, "f32");
        let ns = BTreeMap::from([
            (key("sine"), 24.0),
            (key("small-sine"), 30.0),
            (key("noise"), 26.0),
        ]);
        let g = host_goal(&ns, Some(20.0));
        assert_eq!(g.measured, Some(1.5));
        assert_eq!(g.limit, HOST_BUSHING_NS / REFERENCE_NS);
        assert!(g.note.contains("worst input, small-sine"), "{}", g.note);
        // The bound in this run's ns: 20 ns scaled by the reference.
        let here = format!("so {:.1} ns on this machine", 20.0 / REFERENCE_NS * 20.0);
        assert!(g.note.contains(&here), "{}", g.note);
        assert!(host_goal(&ns, None).measured.is_none());
        assert!(!host_goal(&BTreeMap::new(), Some(20.0)).met());
        // An input not timed is no bound met on the other two.
        let two = BTreeMap::from([(key("sine"), 1.0), (key("noise"), 1.0)]);
        assert!(!host_goal(&two, Some(20.0)).met());
    }
}
