//! The protocol scenes of `scenes/seed000/` (issue 6, build item 5): the
//! Table 3.1 materials carry the identified parameters, and the chapter 1
//! illustrations show what the thesis says they show.

mod common;

use std::f64::consts::SQRT_2;

use bushing_sim::family::xf::Xf;
use bushing_sim::scene::{BackboneSpec, Effect};
use bushing_sim::validate::{self, Outcome};
use bushing_sim::{Scene, probe, run};
use common::root;

/// Carroll's law (c1 I1 + c2 I1^4 + c3 sqrt(I2)) of one Table 3.1 material.
struct Material {
    c1: f64,
    c2: f64,
    c3: f64,
    /// (f in Hz, g, eps_f) of the cells of Table 3.1.
    cells: [(f64, f64, f64); 4],
}

const M1: Material = Material {
    c1: 0.37,
    c2: 0.0,
    c3: 2.2,
    cells: [
        (0.005, 0.296, 2.5e-2),
        (0.5, 0.0, 4.4e-2),
        (5.0, 0.092, 2.6e-3),
        (50.0, 0.0, 1.7e-4),
    ],
};
const M2: Material = Material {
    c1: 0.0,
    c2: 0.0,
    c3: 3.55,
    cells: [
        (0.005, 0.306, 2.2e-2),
        (0.5, 0.0, 1.9e-2),
        (5.0, 0.395, 2.3e-3),
        (50.0, 0.0, 1.7e-4),
    ],
};

impl Material {
    fn w1(&self, i1: f64) -> f64 {
        self.c1 + 4.0 * self.c2 * i1.powi(3)
    }
    fn w2(&self, i2: f64) -> f64 {
        self.c3 / (2.0 * i2.sqrt())
    }
    /// Shear stress (MPa) at shear strain γ: 2γ (W1 + W2), I1 = I2 = 3 + γ².
    fn shear(&self, gamma: f64) -> f64 {
        let i = 3.0 + gamma * gamma;
        2.0 * gamma * (self.w1(i) + self.w2(i))
    }
    /// Nominal stress (MPa) in incompressible uniaxial traction at ε = λ - 1.
    fn traction(&self, eps: f64) -> f64 {
        let l = 1.0 + eps;
        let (i1, i2) = (l * l + 2.0 / l, 2.0 * l + 1.0 / (l * l));
        2.0 * (l - 1.0 / (l * l)) * (self.w1(i1) + self.w2(i2) / l)
    }
}

fn load(name: &str) -> Scene {
    Scene::load(&root().join("scenes/seed000").join(name)).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn table_3_1_scenes_carry_the_identified_parameters() {
    let mut checked = 0;
    for path in common::scene_files() {
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        let material = match stem.get(..3) {
            Some("m1-") => &M1,
            Some("m2-") => &M2,
            _ if stem.starts_with("fig-1-16") || stem.starts_with("fig-1-2") => &M1,
            _ => continue,
        };
        if stem.starts_with("fig-1-21") {
            continue;
        }
        let scene = Scene::load(&path).unwrap();
        let shear = stem.contains("shear");
        let BackboneSpec::Spline { x, force } = &scene.backbone else {
            panic!("{stem}: not a spline backbone");
        };
        assert!(x.len() >= 40, "{stem}");
        for (&x, &f) in x.iter().zip(force) {
            let want = if shear {
                material.shear(x)
            } else {
                material.traction(x)
            };
            assert!(
                (f - want).abs() <= 1e-10,
                "{stem}: F({x}) = {f}, Carroll {want}"
            );
        }
        // Small strain: the shear modulus mu0 of the reference notes.
        let mu0 = material.shear(1e-6) / 1e-6;
        assert!((mu0 - if material.c1 > 0.0 { 2.01 } else { 2.05 }).abs() < 5e-3);
        // The x_f cells: those of Table 3.1 with g > 0, x_f = k eps_f.
        let k = if shear { SQRT_2 } else { (2.0f64 / 3.0).sqrt() };
        for effect in scene.effects() {
            if let Effect::Xf(Xf { cells, .. }) = effect {
                let want: Vec<_> = material.cells.iter().filter(|c| c.1 > 0.0).collect();
                assert_eq!(cells.len(), want.len(), "{stem}");
                for (c, &&(f, g, eps)) in cells.iter().zip(&want) {
                    assert!(
                        (c.omega - std::f64::consts::TAU * f).abs() < 1e-12,
                        "{stem}"
                    );
                    assert_eq!(c.g, g, "{stem}");
                    assert!((c.x_f - k * eps).abs() < 1e-10, "{stem}: x_f {}", c.x_f);
                }
            }
        }
        checked += 1;
    }
    // 16 protocol scenes and the Figs 1.16, 1.24 (twice) and 1.25 scenes.
    assert_eq!(checked, 16 + 4);
}

/// Mean storage modulus of the modulus points at `amplitude` and `mean`.
fn storage(points: &[probe::ModulusPoint], amplitude: f64, mean: f64, freq: f64) -> f64 {
    let sel: Vec<f64> = points
        .iter()
        .filter(|p| {
            p.amplitude_mm == amplitude && (p.mean_mm - mean).abs() < 0.01 && p.frequency_hz == freq
        })
        .map(|p| p.storage)
        .collect();
    assert!(
        sel.len() >= 3,
        "{} points at {amplitude} {mean} {freq}",
        sel.len()
    );
    sel.iter().sum::<f64>() / sel.len() as f64
}

fn modulus(name: &str) -> Vec<probe::ModulusPoint> {
    let scene = load(name);
    let out = std::env::temp_dir().join(format!("bushing-protocol-{name}-{}", std::process::id()));
    let summary = run::run(&scene, &out).unwrap();
    std::fs::remove_dir_all(&out).ok();
    summary.modulus
}

#[test]
fn fig_1_24_payne_effect_comes_from_the_xf_cells() {
    // Seed 000 §1.5.3: the modulus is lower at 10 % than at 2.5 % (Payne);
    // with x_f -> infinity (plain Maxwell cells) the means are the same.
    let payne = modulus("fig-1-24-payne.toml");
    let plain = modulus("fig-1-24-no-xf.toml");
    for preload in [0.0, 0.15] {
        let (small, large) = (
            storage(&payne, 0.025, preload, 1.0),
            storage(&payne, 0.1, preload, 1.0),
        );
        let drop = 1.0 - large / small;
        let (small0, large0) = (
            storage(&plain, 0.025, preload, 1.0),
            storage(&plain, 0.1, preload, 1.0),
        );
        let drop0 = 1.0 - large0 / small0;
        println!(
            "preload {preload}: K' {small:.4} -> {large:.4} MPa ({:.1} %), without x_f {small0:.4} -> {large0:.4} ({:.2} %)",
            100.0 * drop,
            100.0 * drop0
        );
        assert!(drop > 0.15, "Payne drop {drop}");
        assert!(drop0.abs() < 0.01, "without x_f {drop0}");
    }
}

#[test]
fn fig_1_25_frequency_shifts_the_modulus_up() {
    let points = modulus("fig-1-25-frequency.toml");
    let k: Vec<f64> = [0.5, 1.0, 10.0]
        .iter()
        .map(|&f| storage(&points, 0.1, 0.0, f))
        .collect();
    println!("K' at 0.5, 1, 10 Hz: {k:?}");
    // The modulus shifts up with frequency, but with Table 3.1 only
    // slightly: at 10 % the 5 Hz cell (x_f = 0.21 %) slides over most of
    // the cycle, where omega-hat = omega + |x'|/x_f is set by the rate
    // term (about 3000 1/s at 10 Hz against omega = 31 1/s), so the cell
    // is rate independent there and carries no viscous frequency effect.
    assert!(k[0] < k[1] && k[1] < k[2], "{k:?}");
    assert!(k[2] / k[0] - 1.0 < 0.005, "{k:?}");
}

#[test]
fn fig_1_21_loop_matches_the_closed_form_of_the_four_cells() {
    let scene = load("fig-1-21-xf-cells.toml");
    let report = validate::validate(&scene).unwrap();
    let check = report.checks.first().unwrap();
    let Outcome::Compared {
        reference,
        measured,
    } = check.outcome
    else {
        panic!("{report}");
    };
    // Reference notes: F_p = 0.1 + 0.48201 + 0.76159 + 0.96454 N.
    assert!((reference - 2.30814).abs() < 1e-5, "{reference}");
    assert!((measured / reference - 1.0).abs() < 1e-4, "{report}");
    // Energy per steady cycle: 0.36 + 1.03597 + 0.95362 + 0.42554 mJ.
    let out = std::env::temp_dir().join(format!("bushing-fig121-{}", std::process::id()));
    run::run(&scene, &out).unwrap();
    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    std::fs::remove_dir_all(&out).ok();
    let energy: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
        .collect();
    // 2000 steps per cycle: cycle 5 is rows 8000..10000.
    let cycle = energy[9999] - energy[7999];
    println!("energy per cycle {cycle:.5} mJ");
    assert!((cycle - 2.77513).abs() < 2e-3 * 2.77513, "{cycle}");
}

#[test]
fn multi_step_holds_relax_towards_the_long_term_branch() {
    for (name, material, levels) in [
        ("m1-shear-multi-step.toml", &M1, 10),
        ("m2-shear-multi-step.toml", &M2, 10),
    ] {
        let scene = load(name);
        let g0 = 1.0 - material.cells.iter().map(|c| c.1).sum::<f64>();
        let out = std::env::temp_dir().join(format!("bushing-ms-{name}-{}", std::process::id()));
        run::run(&scene, &out).unwrap();
        let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
        std::fs::remove_dir_all(&out).ok();
        let rows: Vec<Vec<f64>> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        // One row per second; each step is 20 s of ramp and 360 s of hold.
        for k in 0..levels {
            let start = rows[(k * 380 + 20) - 1].clone();
            let end = rows[(k * 380 + 380) - 1].clone();
            let level = 0.1 * (k + 1) as f64;
            assert!((start[1] - level).abs() < 1e-9 && (end[1] - level).abs() < 1e-9);
            let long_term = g0 * material.shear(level);
            // The elastic column is g0 F_inf at the level (the spline's
            // knot value).
            assert!((end[3] - long_term).abs() < 1e-9, "{name}");
            // At the end of the ramp the cells carry a share of the force;
            // after 360 s (11 time constants of the 0.005 Hz cell) the
            // force has relaxed onto the long-term branch from above.
            let (excess_start, excess_end) = (start[2] / long_term - 1.0, end[2] / long_term - 1.0);
            if k == 0 || k == levels - 1 {
                println!("{name} level {level}: excess {excess_start:.4} -> {excess_end:.2e}");
            }
            assert!(excess_start > 0.01, "{name} level {level}: {excess_start}");
            // Held still, a cell's force decays as exp(-omega t) (omega-hat =
            // omega without motion): the 5 Hz cell's share is gone, the slow
            // cell's is at most exp(-2 pi 0.005 360) of the start excess.
            let bound = (-std::f64::consts::TAU * 0.005 * 360.0).exp() * excess_start;
            assert!(
                excess_end > 0.0 && excess_end <= bound * (1.0 + 1e-9),
                "{name} level {level}: {excess_end} > {bound}"
            );
        }
    }
}

/// The harmonic-balance table of the seed 004 §2.2 oscillator (reference
/// notes §4.1): amplitude, frequency (Hz), damping (%).
const HB_TABLE: [(f64, f64, f64); 8] = [
    (0.3, 0.38937, 0.1274),
    (0.5, 0.38792, 0.3669),
    (0.75, 0.38587, 0.6390),
    (1.0, 0.38375, 0.9064),
    (1.5, 0.37941, 1.4370),
    (2.0, 0.37500, 1.9826),
    (3.0, 0.36795, 2.3710),
    (5.0, 0.36202, 1.9645),
];

/// Harmonic balance of the oscillator at amplitude `p`, frequency (Hz)
/// and damping (%): each Jenkins cell (stiffness 0.05, slip displacement
/// phi) contributes its first-harmonic stiffness (0.05/π)(β − sin 2β / 2),
/// cos β = 1 − 2 phi/p, and its Masing energy 4 (0.05 phi)(p − phi) once
/// it slips; ξ = D / (2π k p²).
fn hb(p: f64) -> (f64, f64) {
    let (mut k, mut d) = (5.0, 0.0);
    for i in 0..20 {
        let phi = 0.2 + 1.8 * i as f64 / 19.0;
        if p <= phi {
            k += 0.05;
        } else {
            let b = (1.0 - 2.0 * phi / p).acos();
            k += 0.05 / std::f64::consts::PI * (b - (2.0 * b).sin() / 2.0);
            d += 4.0 * 0.05 * phi * (p - phi);
        }
    }
    (
        k.sqrt() / std::f64::consts::TAU,
        100.0 * d / (std::f64::consts::TAU * k * p * p),
    )
}

#[test]
fn the_harmonic_balance_reference_reproduces_the_seed_table() {
    for (p, f, z) in HB_TABLE {
        let (fh, zh) = hb(p);
        assert!(
            (fh - f).abs() <= 5e-6 && (zh - z).abs() <= 5e-5,
            "{p}: {fh} {zh}"
        );
    }
}

#[test]
fn seed_004_iwan_oscillator_decays_along_the_harmonic_balance_curves() {
    let scene = Scene::load(&root().join("scenes/seed004/iwan-oscillator.toml")).unwrap();
    let out = std::env::temp_dir().join(format!("bushing-iwan-osc-{}", std::process::id()));
    let summary = run::run(&scene, &out).unwrap();
    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    std::fs::remove_dir_all(&out).ok();
    assert_eq!(summary.refused, 0);
    let rows: Vec<(f64, f64)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            (v[0], v[1])
        })
        .collect();
    // Positive peaks, refined by a parabola through three samples.
    let mut peaks = Vec::new();
    for w in rows.windows(3) {
        let ((t0, a), (_, b), (t2, c)) = (w[0], w[1], w[2]);
        if b > 0.0 && b >= a && b > c {
            let h = 0.5 * (t2 - t0);
            let d = 0.5 * (a - c) / (a - 2.0 * b + c);
            peaks.push((t0 + h * (1.0 + d), b - 0.25 * (a - c) * d));
        }
    }
    assert!(peaks.len() > 100, "{} peaks", peaks.len());
    let (mut worst_f, mut worst_z) = (0.0f64, 0.0f64);
    for w in peaks.windows(2) {
        let ((t0, p0), (t1, p1)) = (w[0], w[1]);
        let amplitude = (p0 * p1).sqrt();
        let f = 1.0 / (t1 - t0);
        let zeta = 100.0 * (p0 / p1).ln() / std::f64::consts::TAU;
        let (f_hb, z_hb) = hb(amplitude);
        worst_f = worst_f.max((f / f_hb - 1.0).abs());
        worst_z = worst_z.max((zeta - z_hb).abs());
    }
    println!(
        "{} cycles from {:.3} to {:.3}: worst frequency error {:.3} %, worst damping error {:.3} points",
        peaks.len() - 1,
        peaks[0].1,
        peaks.last().unwrap().1,
        100.0 * worst_f,
        worst_z
    );
    // The free decay sees each cycle at a falling amplitude and the
    // damping of the energy ratio D/(2 pi p^2 f'), up to 0.21 points above
    // harmonic balance (reference notes §4.9, seed 004 §3.3).
    assert!(worst_f < 1e-3, "frequency {worst_f}");
    assert!(worst_z < 0.25, "damping {worst_z}");
    // The damping vanishes as the amplitude falls to 0.2, where the first
    // cell stops slipping: the decay creeps down to it from above.
    let last = peaks.len() - 1;
    assert!((0.2..0.205).contains(&peaks[last].1), "{:?}", peaks[last]);
    let tail = &peaks[last - 5..];
    assert!(tail[0].1 / tail[5].1 - 1.0 < 1e-3, "{tail:?}");
}
