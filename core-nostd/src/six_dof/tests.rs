extern crate std;

use super::*;
use crate::{IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial};

type Axis = Bushing<f64, Polynomial<f64, 4>, (MaxwellBank<f64, 2>, IwanBank<f64, 2>)>;

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
