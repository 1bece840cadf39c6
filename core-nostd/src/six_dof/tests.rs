extern crate std;

use super::*;
use crate::{IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial};

type Effects = (MaxwellBank<f64, 2>, IwanBank<f64, 2>);
type Axis = Bushing<f64, Polynomial<f64, 4>, Effects>;
type Mount = SixDof<f64, Polynomial<f64, 4>, Effects>;
type MountState = SixDofState<f64, <Effects as Effect<f64>>::State>;

/// An odd, hardening law with two Maxwell cells and two Jenkins cells:
/// stiffness `k`, cubic term `c`, slip forces scaled by `slip`.
fn axis(k: f64, c: f64, slip: f64) -> Axis {
    Bushing::new(
        Polynomial::new(&[0.0, k, 0.0, c], (-1e3, 1e3)).unwrap(),
        (
            MaxwellBank::new(
                MaxwellForm::RateExactRamp,
                &[MaxwellSpec::hz(1.0, 0.1), MaxwellSpec::hz(20.0, 0.15)],
                1e-3,
            )
            .unwrap(),
            IwanBank::new(&[
                IwanCellSpec::new(0.05, slip),
                IwanCellSpec::new(0.05, 4.0 * slip),
            ])
            .unwrap(),
        ),
    )
    .unwrap()
}

/// Six different laws: stiffer radially than axially, different torsion
/// and tilt stiffnesses (N, mm, rad).
fn anisotropic() -> [Axis; 6] {
    [
        axis(300.0, 5.0, 2.0),
        axis(120.0, 1.0, 1.0),
        axis(800.0, 20.0, 5.0),
        axis(4.0e4, 1.0e3, 50.0),
        axis(1.5e4, 0.0, 20.0),
        axis(9.0e4, 4.0e3, 80.0),
    ]
}

/// Two nodes moving apart and rotating against each other: relative
/// rotations up to about 1.3 rad about a wandering axis, translations of
/// a few mm, both nodes also moving as a whole.
fn poses(i: usize) -> (Pose<f64>, Pose<f64>) {
    let t = i as f64 * 0.01;
    let a = Pose {
        position: [10.0 + 2.0 * libm::sin(t), -3.0, 1.0 + libm::cos(0.7 * t)],
        orientation: Quat::from_rotation_vector([
            0.3 * libm::sin(0.5 * t),
            -0.2,
            0.4 + 0.2 * libm::cos(t),
        ]),
    };
    let b = Pose {
        position: [12.0 + 3.0 * libm::sin(1.3 * t), -1.0 + libm::cos(t), 2.0],
        orientation: Quat::from_rotation_vector([
            -0.5 + 0.6 * libm::sin(t),
            0.7 * libm::cos(0.8 * t),
            -0.3 + 0.4 * libm::sin(1.7 * t),
        ]),
    };
    (a, b)
}

const OFFSET_A: [f64; 3] = [5.0, -2.0, 3.0];
const OFFSET_B: [f64; 3] = [-4.0, 1.0, -6.0];

/// Runs the bushing with node order (A, B) and (B, A) over the same
/// motion: the largest difference of the loads on each physical node,
/// over the largest load, and the largest relative rotation seen.
fn swap_difference(connectivity: Connectivity) -> (f64, f64) {
    let ab = SixDof::new(anisotropic(), [OFFSET_A, OFFSET_B], connectivity).unwrap();
    let ba = SixDof::new(anisotropic(), [OFFSET_B, OFFSET_A], connectivity).unwrap();
    let (a0, b0) = poses(0);
    let (mut s_ab, mut s_ba) = (ab.state_at(&a0, &b0), ba.state_at(&b0, &a0));
    let (mut diff, mut scale_, mut angle) = (0.0f64, 0.0f64, 0.0f64);
    for i in 1..400 {
        let (a, b) = poses(i);
        let o1 = ab.step(&mut s_ab, &a, &b);
        let o2 = ba.step(&mut s_ba, &b, &a);
        let th = &o1.strain[3..];
        angle = angle.max(libm::sqrt(th.iter().map(|x| x * x).sum::<f64>()));
        // Node A is node 1 of `ab` and node 2 of `ba`.
        for (n1, n2) in [(0, 1), (1, 0)] {
            for c in 0..3 {
                let pairs = [
                    (o1.loads.force[n1][c], o2.loads.force[n2][c]),
                    (o1.loads.moment[n1][c], o2.loads.moment[n2][c]),
                ];
                for (x, y) in pairs {
                    diff = diff.max((x - y).abs());
                    scale_ = scale_.max(x.abs());
                }
            }
        }
        // The local loads are mirrored.
        if connectivity == Connectivity::Invariant {
            for (x, y) in o1.local.iter().zip(&o2.local) {
                assert!((x + y).abs() <= 1e-12 * scale_, "{x} {y}");
            }
        }
    }
    (diff / scale_, angle)
}

#[test]
fn invariant_form_does_not_depend_on_the_node_order() {
    let (rel, angle) = swap_difference(Connectivity::Invariant);
    std::println!(
        "invariant: swap difference {rel:.2e} of the largest load, |θ| up to {angle:.2} rad"
    );
    assert!(angle > 1.0, "large rotations: {angle}");
    assert!(rel <= 1e-12, "{rel}");
}

#[test]
fn attached_form_depends_on_the_node_order() {
    let (rel, _) = swap_difference(Connectivity::Attached);
    std::println!("attached: swap difference {rel:.2e} of the largest load");
    // The seed's finding: anisotropic laws referred to node 1 change when
    // the nodes are swapped, by a fraction of the load itself here.
    assert!(rel > 0.05, "{rel}");
}

#[test]
fn loads_balance_in_both_forms() {
    for connectivity in [Connectivity::Attached, Connectivity::Invariant] {
        let b = SixDof::new(anisotropic(), [OFFSET_A, OFFSET_B], connectivity).unwrap();
        let (a0, b0) = poses(0);
        let mut s = b.state_at(&a0, &b0);
        for i in 1..200 {
            let (na, nb) = poses(i);
            let o = b.step(&mut s, &na, &nb);
            let l = o.loads;
            let sum_f = add(l.force[0], l.force[1]);
            let sum_m = add(
                add(cross(na.position, l.force[0]), l.moment[0]),
                add(cross(nb.position, l.force[1]), l.moment[1]),
            );
            let big = l.moment[0]
                .iter()
                .chain(&l.moment[1])
                .fold(1.0f64, |m, x| m.max(x.abs()));
            for c in 0..3 {
                assert!(
                    sum_f[c].abs() <= 1e-12 * big,
                    "{connectivity:?} force {sum_f:?}"
                );
                assert!(
                    sum_m[c].abs() <= 1e-12 * big,
                    "{connectivity:?} moment {sum_m:?}"
                );
            }
        }
    }
}

#[test]
fn small_rotations_and_translations_follow_each_axis_law() {
    // Node 1 at rest at the origin; node 2 turned by 1e-3 rad about z and
    // moved 0.01 mm along y: each axis sees its own strain.
    let b = SixDof::new(anisotropic(), [[0.0; 3]; 2], Connectivity::Invariant).unwrap();
    let rest = Pose {
        position: [0.0; 3],
        orientation: Quat::identity(),
    };
    let mut s = b.state_at(&rest, &rest);
    let moved = Pose {
        position: [0.0, 0.01, 0.0],
        orientation: Quat::from_rotation_vector([0.0, 0.0, 1e-3]),
    };
    let o = b.step(&mut s, &rest, &moved);
    assert!((o.strain[5] - 1e-3).abs() < 1e-15);
    // The mid frame is turned by half the rotation: y is seen at 0.5 mrad.
    assert!((o.strain[1] - 0.01 * libm::cos(0.5e-3)).abs() < 1e-15);
    assert!((o.strain[0] - 0.01 * libm::sin(0.5e-3)).abs() < 1e-15);
    for (k, (&x, &f)) in o.strain.iter().zip(&o.local).enumerate() {
        let alone = b
            .axis(k)
            .unwrap()
            .step(&mut b.axis(k).unwrap().state_at(0.0), x);
        assert_eq!(f, alone.force, "axis {k}");
    }
    // Node 2 gets the reaction: minus the force along (about) y, minus
    // the moment about z.
    assert!(o.loads.force[1][1] < 0.0 && o.loads.moment[1][2] < 0.0);
}

#[test]
fn no_relative_motion_gives_no_load() {
    let b = SixDof::new(anisotropic(), [OFFSET_A, OFFSET_A], Connectivity::Invariant).unwrap();
    let (a, _) = poses(7);
    let mut s = b.state_at(&a, &a);
    let o = b.step(&mut s, &a, &a);
    for v in o.loads.force.iter().chain(&o.loads.moment) {
        assert!(v.iter().all(|x| x.abs() < 1e-12), "{o:?}");
    }
}

#[test]
fn quaternions_rotate_as_rotation_vectors_do() {
    let q = Quat::<f64>::from_rotation_vector([0.0, 0.0, core::f64::consts::FRAC_PI_2]);
    let r = q.rotate([1.0, 0.0, 0.0]);
    assert!((r[0]).abs() < 1e-15 && (r[1] - 1.0).abs() < 1e-15);
    let back = q.rotate_back(r);
    assert!((back[0] - 1.0).abs() < 1e-15 && back[1].abs() < 1e-15);
    // Composition: two quarter turns about z are a half turn.
    let h = (q * q).rotate([1.0, 0.0, 0.0]);
    assert!((h[0] + 1.0).abs() < 1e-15);
}

#[test]
fn non_finite_offsets_are_refused_by_name() {
    let e = SixDof::new(
        anisotropic(),
        [[0.0; 3], [0.0, f64::NAN, 0.0]],
        Connectivity::Invariant,
    );
    assert_eq!(
        e.map(|_| ()),
        Err(ParamError::NotFinite {
            param: Param::item("offset", 4)
        })
    );
}

/// The loads as one vector (f₁, m₁, f₂, m₂).
fn flat(l: &Loads<f64>) -> [f64; 12] {
    let mut out = [0.0; 12];
    let parts = [l.force[0], l.moment[0], l.force[1], l.moment[1]];
    for (o, x) in out.iter_mut().zip(parts.iter().flatten()) {
        *o = *x;
    }
    out
}

/// `p` moved by `u` and turned by the global rotation vector `r`.
fn moved(p: &Pose<f64>, u: [f64; 3], r: [f64; 3]) -> Pose<f64> {
    Pose {
        position: add(p.position, u),
        orientation: Quat::from_rotation_vector(r) * p.orientation,
    }
}

/// Largest difference between the tangent and central differences of the
/// trial loads (step 1e-6), over the largest tangent entry.
fn tangent_error(b: &Mount, s: &MountState, n1: &Pose<f64>, n2: &Pose<f64>) -> f64 {
    let (out, _) = b.trial(s, n1, n2);
    let k = b.tangent(&out, n1, n2).expect("a usable configuration");
    let h = 1e-6;
    let (mut worst, mut big) = (0.0f64, 0.0f64);
    for j in 0..12 {
        let mut e = [0.0; 3];
        e[j % 3] = h;
        let z = [0.0; 3];
        let shift = |sign: f64| {
            let e = scale(e, sign);
            let (u, r) = if (j / 3) % 2 == 0 { (e, z) } else { (z, e) };
            if j < 6 {
                (moved(n1, u, r), *n2)
            } else {
                (*n1, moved(n2, u, r))
            }
        };
        let ((p1, p2), (m1, m2)) = (shift(1.0), shift(-1.0));
        let plus = flat(&b.trial(s, &p1, &p2).0.loads);
        let minus = flat(&b.trial(s, &m1, &m2).0.loads);
        for i in 0..12 {
            let fd = (plus[i] - minus[i]) / (2.0 * h);
            worst = worst.max((k[i][j] - fd).abs());
            big = big.max(k[i][j].abs());
        }
    }
    worst / big
}

#[test]
fn tangent_matches_finite_differences() {
    for connectivity in [Connectivity::Attached, Connectivity::Invariant] {
        let b = SixDof::new(anisotropic(), [OFFSET_A, OFFSET_B], connectivity).unwrap();
        // After a loaded history, at a relative rotation of about a radian.
        let (a0, b0) = poses(0);
        let mut s = b.state_at(&a0, &b0);
        for i in 1..100 {
            let (na, nb) = poses(i);
            b.step(&mut s, &na, &nb);
        }
        let (na, nb) = poses(100);
        let large = tangent_error(&b, &s, &na, &nb);
        // From rest, a small rotation (the series branch, φ < 0.1).
        let rest = b.state_at(&a0, &a0);
        let near = moved(&a0, [0.3, -0.2, 0.1], [0.02, -0.03, 0.01]);
        let small = tangent_error(&b, &rest, &a0, &near);
        std::println!(
            "{connectivity:?}: tangent error {large:.1e} (large rotation), {small:.1e} (small)"
        );
        assert!(
            large < 1e-6 && small < 1e-6,
            "{connectivity:?}: {large} {small}"
        );
    }
}

#[test]
fn unusable_configurations_are_refused_and_the_loads_held() {
    let b = SixDof::new(anisotropic(), [OFFSET_A, OFFSET_B], Connectivity::Invariant).unwrap();
    let (a0, b0) = poses(0);
    let mut s = b.state_at(&a0, &b0);
    let (a1, b1) = poses(30);
    let held = b.step(&mut s, &a1, &b1).loads;
    let before = s.clone();
    let mut nan = b1;
    nan.position[1] = f64::NAN;
    let o = b.step(&mut s, &a1, &nan);
    assert_eq!(o.loads, held);
    assert_eq!(o.dissipated, 0.0);
    assert!(s.faults().contains(Faults::NON_FINITE_INPUT));
    let mut huge = b1;
    huge.position[0] = 1e300;
    b.step(&mut s, &a1, &huge);
    assert!(s.faults().contains(Faults::OUT_OF_RANGE));
    let mut scaled = b1;
    scaled.orientation.w *= 1.01;
    assert_eq!(b.step(&mut s, &a1, &scaled).loads, held);
    // Nothing else moved.
    for k in 0..6 {
        assert_eq!(s.axis(k), before.axis(k));
    }
    assert_eq!(s.loads(), held);
    s.clear_faults();
    assert!(s.faults().is_empty());
    // The next usable step goes on from the held state.
    let (a2, b2) = poses(31);
    assert!(b.step(&mut s, &a2, &b2).loads.force[0][0].is_finite());
}

#[test]
fn offsets_and_positions_beyond_their_share_of_the_guard_are_refused() {
    // An offset component is refused beyond a sixteenth of the guard (in
    // the working type), naming its node and component.
    let g = <f64 as Real>::GUARD;
    let far = SixDof::new(
        anisotropic(),
        [OFFSET_A, [0.0, 0.0, -1.01 * g / 16.0]],
        Connectivity::Invariant,
    );
    match far {
        Err(ParamError::OutOfRange { param, max, .. }) => {
            assert_eq!(param, Param::item("offset", 5));
            assert_eq!(max, g / 16.0);
        }
        other => panic!("{other:?}"),
    }
    let near = [OFFSET_A, [0.0, 0.0, -0.99 * g / 16.0]];
    assert!(SixDof::new(anisotropic(), near, Connectivity::Invariant).is_ok());
    // A position beyond a quarter of the guard is refused as out of range
    // (not as a NaN); both nodes just within it are taken.
    let b = SixDof::new(anisotropic(), [OFFSET_A, OFFSET_B], Connectivity::Attached).unwrap();
    let (a0, b0) = poses(0);
    let mut s = b.state_at(&a0, &b0);
    let held = s.loads();
    let mut beyond = b0;
    beyond.position[2] = 1.01 * g / 4.0;
    assert_eq!(b.step(&mut s, &a0, &beyond).loads, held);
    assert!(s.faults().contains(Faults::OUT_OF_RANGE));
    assert!(!s.faults().contains(Faults::NON_FINITE_INPUT));
    s.clear_faults();
    let (mut near1, mut near2) = (a0, b0);
    near1.position[2] = 0.99 * g / 4.0;
    near2.position[2] = 0.99 * g / 4.0;
    b.step(&mut s, &near1, &near2);
    assert!(s.faults().is_empty(), "{:?}", s.faults());
}

#[test]
fn a_strain_beyond_the_guard_is_refused_before_any_axis_steps() {
    // Positions within a quarter of the guard and offsets within a
    // sixteenth can still give a local strain beyond it: the nodes on the
    // diagonal, node 1's x axis turned onto it and both offsets along it.
    // The axes take the strains unchecked (`Bushing::step_within`), so the
    // 6-DOF check must refuse the step before any of them moves.
    let g = <f64 as Real>::GUARD;
    let turn = libm::acos(1.0 / libm::sqrt(3.0)) / libm::sqrt(2.0);
    let (c, o) = (0.2495 * g, 0.99 * g / 16.0);
    let at = |c: f64, orientation| Pose {
        position: [c; 3],
        orientation,
    };
    let node1 = at(-c, Quat::from_rotation_vector([0.0, -turn, turn]));
    let node2 = at(c, Quat::identity());
    let b = SixDof::new(
        anisotropic(),
        [[-o, 0.0, 0.0], [o; 3]],
        Connectivity::Attached,
    )
    .unwrap();
    let (a0, b0) = poses(0);
    let mut s = b.state_at(&a0, &b0);
    let before = s.clone();
    let out = b.step(&mut s, &node1, &node2);
    assert_eq!(out.loads, before.loads());
    assert!(s.faults().contains(Faults::OUT_OF_RANGE));
    for k in 0..6 {
        // Not even refused by the axis: its state, faults and count of
        // refusals are as they were.
        assert_eq!(s.axis(k), before.axis(k));
    }
    // The same configuration 4 % closer together (a strain of 0.99 of
    // the guard) is the axes' to refuse: beyond their backbones' range.
    let (node1, node2) = (
        at(-0.96 * c, node1.orientation),
        at(0.96 * c, node2.orientation),
    );
    let k = b.kinematics(&node1, &node2);
    assert!(
        k.strain[0] > 0.98 * g && k.strain[0] < g,
        "{}",
        k.strain[0] / g
    );
    let mut s = before.clone();
    b.step(&mut s, &node1, &node2);
    assert!(
        s.axis(0)
            .is_some_and(|a| a.faults().contains(Faults::OUT_OF_RANGE))
    );
}
