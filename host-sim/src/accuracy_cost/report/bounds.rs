//! The kernels' bounds of the cost issue ("cost figures that predict the
//! silicon"), judged like the earlier targets on each kernel's worst input
//! and in M4F guest instructions with the estimated cycles beside; the
//! filter-only ratio to the best peer; and the growth of the modal
//! tracker's cost with its number of states.

use super::{Lines, as_accurate, m4f, per_call, per_cell, sig};
use crate::accuracy_cost::Goal;
use crate::accuracy_cost::firmware::PeerLine;

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
}
