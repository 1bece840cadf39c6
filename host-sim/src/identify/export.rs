//! The identified model written three ways, from the same printed
//! numbers (each f64 in its shortest form that reads back to the same
//! bits):
//!
//! - `model.toml`: the model part of a scene, with a sine profile to
//!   replace by any other; `bushing-sim run` runs it as is;
//! - `model.rs`: the same parameters as constants and one generic
//!   constructor of the core's const-size types, for firmware;
//! - `model.h`: the same numbers as C constants.
//!
//! The identification replays its tests on the model read back from
//! `model.toml`, so the report's figures are those of the files.

use std::f64::consts::TAU;
use std::fmt::Write as _;

use super::class::Candidate;
use super::report::Preprocessed;
use crate::family::backbone::BackboneSpec;
use crate::family::turning_points::STACK_DEPTH;

/// Shortest text that reads back to the same f64.
fn num(v: f64) -> String {
    format!("{v:?}")
}

/// The frequency in Hz written for a corner `omega` (rad/s).
fn hz(omega: f64) -> f64 {
    omega / TAU
}

/// A sine profile for the written scene: amplitude (mm) and frequency (Hz).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Demo {
    /// Amplitude, mm.
    pub amplitude_mm: f64,
    /// Frequency, Hz.
    pub frequency_hz: f64,
}

/// The sine the written scene runs: the middle tested frequency at the
/// largest amplitude (1 mm at 5 Hz without sines).
pub fn demo(pre: &Preprocessed) -> Demo {
    let mut f: Vec<f64> = pre.sines.iter().map(|(_, s)| s.frequency_hz).collect();
    f.sort_by(f64::total_cmp);
    let a = pre
        .sines
        .iter()
        .map(|(_, s)| s.amplitude_mm)
        .fold(0.0, f64::max);
    Demo {
        amplitude_mm: if a > 0.0 {
            (a * 1e3).round() / 1e3
        } else {
            1.0
        },
        frequency_hz: f.get(f.len() / 2).copied().unwrap_or(5.0),
    }
}

/// `model.toml`.
pub fn toml(m: &Candidate, campaign: &str, demo: Demo) -> String {
    let name = campaign.replace(['"', '\\', '\n'], " ");
    let mut s = format!(
        "# Identified by `bushing-sim identify` from the campaign \"{name}\".\n\
         # The model part of a scene: [run] and [profile] may be replaced by any\n\
         # rate and profile. Units: mm, N, s.\n\
         title = \"Identified: {name}\"\n\n\
         [run]\nrate_hz = 1000\nnumber = \"f64\"\n\n[backbone]\n"
    );
    let list = |v: &[f64]| v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ");
    match &m.backbone {
        BackboneSpec::Spline { x, force } => {
            let _ = writeln!(s, "type = \"spline\"\nx = [{}]", list(x));
            let _ = writeln!(s, "force = [{}]", list(force));
        }
        BackboneSpec::Polynomial {
            coefficients,
            range,
        } => {
            let _ = writeln!(
                s,
                "type = \"polynomial\"\ncoefficients = [{}]",
                list(coefficients)
            );
            let _ = writeln!(s, "range = [{}]", list(range));
        }
    }
    if !m.maxwell.is_empty() {
        s.push_str("\n[[effects]]\ntype = \"maxwell\"\nform = \"rate-exact-ramp\"\ncells = [\n");
        for c in &m.maxwell {
            let _ = writeln!(s, "  {{ f_hz = {}, g = {} }},", num(hz(c.omega)), num(c.g));
        }
        s.push_str("]\n");
    }
    if !m.jenkins.is_empty() {
        s.push_str("\n[[effects]]\ntype = \"iwan\"\nform = \"clamp\"\ncells = [\n");
        for c in &m.jenkins {
            let _ = writeln!(
                s,
                "  {{ g = {}, slip_force = {} }},",
                num(c.g),
                num(c.slip_force)
            );
        }
        s.push_str("]\n");
    }
    if let Some((c, k1)) = m.sts {
        let _ = write!(
            s,
            "\n[[effects]]\ntype = \"turning-points\"\nlaw = \"sts\"\nc = {}\nk1 = {}\n",
            num(c),
            num(k1)
        );
    }
    if !m.xf.is_empty() {
        s.push_str("\n[[effects]]\ntype = \"xf\"\nform = \"exact-ramp\"\ncells = [\n");
        for c in &m.xf {
            let _ = writeln!(
                s,
                "  {{ f_hz = {}, g = {}, x_f = {} }},",
                num(hz(c.omega)),
                num(c.g),
                num(c.x_f)
            );
        }
        s.push_str("]\n");
    }
    let _ = write!(
        s,
        "\n[profile]\ntype = \"sine\"\namplitude = {}\nfrequency_hz = {}\ncycles = 5\n",
        num(demo.amplitude_mm),
        num(demo.frequency_hz)
    );
    s
}

/// The effects' Rust types and constructor calls, in the scene's order.
fn rust_effects(m: &Candidate) -> (Vec<String>, Vec<String>) {
    let (mut types, mut calls) = (Vec::new(), Vec::new());
    if !m.maxwell.is_empty() {
        types.push(format!("MaxwellBank<T, {}>", m.maxwell.len()));
        calls.push("MaxwellBank::new(MaxwellForm::RateExactRamp, &maxwell_cells(), dt)?".into());
    }
    if !m.jenkins.is_empty() {
        types.push(format!("IwanBank<T, {}>", m.jenkins.len()));
        calls.push("IwanBank::new(&iwan_cells())?".into());
    }
    if m.sts.is_some() {
        types.push(format!("TurningPoints<Sts<T>, {STACK_DEPTH}>"));
        calls.push("TurningPoints::new(Sts::new(STS_C, STS_K1)?, FirstLoading::Masing)".into());
    }
    if !m.xf.is_empty() {
        types.push(format!("XfBank<T, {}>", m.xf.len()));
        calls.push("XfBank::new(XfForm::ExactRamp, &xf_cells(), dt)?".into());
    }
    (types, calls)
}

/// `model.rs`.
pub fn rust(m: &Candidate, campaign: &str) -> String {
    let name = campaign.replace('\n', " ");
    let list = |v: &[f64]| v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ");
    // Plain comments, so that the file can be `include!`d in a module.
    let header = format!(
        "// Identified by `bushing-sim identify` from the campaign \"{name}\":\n\
         // the parameters of `model.toml` as constructor calls of the `bushing`\n\
         // crate. Units: mm, N, s; corners in Hz.\n\n"
    );
    let mut s = String::new();
    let (types, calls) = rust_effects(m);
    let mut imports = vec!["Bushing", "ParamError", "Real"];
    let (backbone_type, backbone_call) = match &m.backbone {
        BackboneSpec::Spline { x, force } => {
            imports.push("MonotoneSpline");
            let _ = writeln!(
                s,
                "/// Backbone knots, mm.\npub const BACKBONE_X_MM: [f64; {}] = [{}];",
                x.len(),
                list(x)
            );
            let _ = writeln!(
                s,
                "/// F^inf at the knots, N.\npub const BACKBONE_F_N: [f64; {}] = [{}];",
                force.len(),
                list(force)
            );
            (
                format!("MonotoneSpline<T, {}>", x.len()),
                "MonotoneSpline::new(&BACKBONE_X_MM, &BACKBONE_F_N)?".to_string(),
            )
        }
        BackboneSpec::Polynomial {
            coefficients,
            range,
        } => {
            imports.push("Polynomial");
            let _ = writeln!(
                s,
                "/// F^inf = c0 + c1 x + ..., N and mm.\npub const BACKBONE_COEFFICIENTS: [f64; {}] = [{}];",
                coefficients.len(),
                list(coefficients)
            );
            let _ = writeln!(
                s,
                "/// Validity range, mm.\npub const BACKBONE_RANGE_MM: (f64, f64) = ({}, {});",
                num(range[0]),
                num(range[1])
            );
            (
                format!("Polynomial<T, {}>", coefficients.len()),
                "Polynomial::new(&BACKBONE_COEFFICIENTS, BACKBONE_RANGE_MM)?".to_string(),
            )
        }
    };
    if !m.maxwell.is_empty() {
        imports.extend(["MaxwellBank", "MaxwellForm", "MaxwellSpec"]);
        let _ = writeln!(
            s,
            "/// Maxwell cells: (corner Hz, fraction g).\npub const MAXWELL_HZ_G: [(f64, f64); {}] = [{}];",
            m.maxwell.len(),
            m.maxwell
                .iter()
                .map(|c| format!("({}, {})", num(hz(c.omega)), num(c.g)))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = writeln!(
            s,
            "\n/// The Maxwell cells as the core's specs.\npub fn maxwell_cells() -> [MaxwellSpec; {}] {{\n    MAXWELL_HZ_G.map(|(f, g)| MaxwellSpec::hz(f, g))\n}}\n",
            m.maxwell.len()
        );
    }
    if !m.jenkins.is_empty() {
        imports.extend(["IwanBank", "IwanCellSpec"]);
        let _ = writeln!(
            s,
            "/// Jenkins cells: (fraction g, slip force N).\npub const IWAN_G_SLIP_N: [(f64, f64); {}] = [{}];",
            m.jenkins.len(),
            m.jenkins
                .iter()
                .map(|c| format!("({}, {})", num(c.g), num(c.slip_force)))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = writeln!(
            s,
            "\n/// The Jenkins cells as the core's specs.\npub fn iwan_cells() -> [IwanCellSpec; {}] {{\n    IWAN_G_SLIP_N.map(|(g, f)| IwanCellSpec::new(g, f))\n}}\n",
            m.jenkins.len()
        );
    }
    if let Some((c, k1)) = m.sts {
        imports.extend(["FirstLoading", "Sts", "TurningPoints"]);
        let _ = writeln!(
            s,
            "/// STS constant C, N²/mm.\npub const STS_C: f64 = {};",
            num(c)
        );
        let _ = writeln!(
            s,
            "/// STS stiffness at a turning point K_1, N/mm.\npub const STS_K1: f64 = {};",
            num(k1)
        );
    }
    if !m.xf.is_empty() {
        imports.extend(["XfBank", "XfForm", "XfSpec"]);
        let _ = writeln!(
            s,
            "/// x_f cells: (corner Hz, fraction g, x_f mm).\npub const XF_HZ_G_XF: [(f64, f64, f64); {}] = [{}];",
            m.xf.len(),
            m.xf.iter()
                .map(|c| format!("({}, {}, {})", num(hz(c.omega)), num(c.g), num(c.x_f)))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = writeln!(
            s,
            "\n/// The x_f cells as the core's specs.\npub fn xf_cells() -> [XfSpec; {}] {{\n    XF_HZ_G_XF.map(|(f, g, x_f)| XfSpec::hz(f, g, x_f))\n}}\n",
            m.xf.len()
        );
    }
    imports.sort_unstable();
    let effects_type = match types.len() {
        0 => "()".to_string(),
        _ => format!("({},)", types.join(", ")),
    };
    let effects_call = match calls.len() {
        0 => "()".to_string(),
        _ => format!("({},)", calls.join(", ")),
    };
    while s.ends_with("\n\n") {
        s.pop();
    }
    // A model of rate-independent effects only does not read its step.
    let unused = if effects_call.contains("dt") {
        ""
    } else {
        "    let _ = dt; // rate independent\n"
    };
    let _ = write!(
        s,
        "\n/// The identified bushing in the number type `T`.\n\
         pub type Model<T> = Bushing<T, {backbone_type}, {effects_type}>;\n\n\
         /// The identified bushing at time step `dt` (s).\n\
         pub fn model<T: Real>(dt: f64) -> Result<Model<T>, ParamError> {{\n\
         {unused}\
         \x20   Bushing::new({backbone_call}, {effects_call})\n}}\n"
    );
    format!("{header}use bushing::{{{}}};\n\n{s}", imports.join(", "))
}

/// `model.h`.
pub fn c_header(m: &Candidate, campaign: &str) -> String {
    let name = campaign.replace(['\n', '*', '/'], " ");
    let list = |v: &[f64]| v.iter().map(|x| c_num(*x)).collect::<Vec<_>>().join(", ");
    let mut s = format!(
        "/* Identified by `bushing-sim identify` from the campaign \"{name}\":\n\
         \x20* the parameters of model.toml as C constants. Units: mm, N, s;\n\
         \x20* corners in Hz (omega = 2 pi f). */\n\
         #ifndef BUSHING_MODEL_H\n#define BUSHING_MODEL_H\n\n"
    );
    match &m.backbone {
        BackboneSpec::Spline { x, force } => {
            let _ = writeln!(s, "#define BUSHING_MODEL_BACKBONE_POINTS {}", x.len());
            let _ = writeln!(
                s,
                "static const double bushing_model_backbone_x_mm[{}] = {{{}}};",
                x.len(),
                list(x)
            );
            let _ = writeln!(
                s,
                "static const double bushing_model_backbone_f_n[{}] = {{{}}};",
                force.len(),
                list(force)
            );
        }
        BackboneSpec::Polynomial {
            coefficients,
            range,
        } => {
            let _ = writeln!(
                s,
                "#define BUSHING_MODEL_BACKBONE_COEFFICIENTS {}",
                coefficients.len()
            );
            let _ = writeln!(
                s,
                "static const double bushing_model_backbone_coefficients[{}] = {{{}}};",
                coefficients.len(),
                list(coefficients)
            );
            let _ = writeln!(
                s,
                "static const double bushing_model_backbone_range_mm[2] = {{{}}};",
                list(range)
            );
        }
    }
    let pairs = |v: Vec<(f64, f64)>| {
        v.iter()
            .map(|(a, b)| format!("{{{}, {}}}", c_num(*a), c_num(*b)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if !m.maxwell.is_empty() {
        let _ = writeln!(s, "#define BUSHING_MODEL_MAXWELL_CELLS {}", m.maxwell.len());
        let _ = writeln!(
            s,
            "/* {{corner Hz, fraction g}} */\nstatic const double bushing_model_maxwell_hz_g[{}][2] = {{{}}};",
            m.maxwell.len(),
            pairs(m.maxwell.iter().map(|c| (hz(c.omega), c.g)).collect())
        );
    }
    if !m.jenkins.is_empty() {
        let _ = writeln!(s, "#define BUSHING_MODEL_IWAN_CELLS {}", m.jenkins.len());
        let _ = writeln!(
            s,
            "/* {{fraction g, slip force N}} */\nstatic const double bushing_model_iwan_g_slip_n[{}][2] = {{{}}};",
            m.jenkins.len(),
            pairs(m.jenkins.iter().map(|c| (c.g, c.slip_force)).collect())
        );
    }
    if let Some((c, k1)) = m.sts {
        let _ = writeln!(
            s,
            "static const double bushing_model_sts_c = {}; /* N^2/mm */",
            c_num(c)
        );
        let _ = writeln!(
            s,
            "static const double bushing_model_sts_k1 = {}; /* N/mm */",
            c_num(k1)
        );
    }
    if !m.xf.is_empty() {
        let _ = writeln!(s, "#define BUSHING_MODEL_XF_CELLS {}", m.xf.len());
        let _ = writeln!(
            s,
            "/* {{corner Hz, fraction g, x_f mm}} */\nstatic const double bushing_model_xf[{}][3] = {{{}}};",
            m.xf.len(),
            m.xf.iter()
                .map(|c| format!("{{{}}}", list(&[hz(c.omega), c.g, c.x_f])))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s.push_str("\n#endif /* BUSHING_MODEL_H */\n");
    s
}

/// A C double literal that reads back to the same bits (17 significant
/// digits).
fn c_num(v: f64) -> String {
    format!("{v:.16e}")
}
