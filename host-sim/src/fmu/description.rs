//! The FMU's variables and its `modelDescription.xml` (FMI 2.0,
//! co-simulation), generated from the model.

use std::fmt::Write as _;

use super::resource::FmuModel;
use crate::plot::sanitize;

/// The FMU's library name in `binaries/<platform>/` (without the
/// extension) and the `modelIdentifier` of its description.
pub const MODEL_IDENTIFIER: &str = "bushing";

/// Value reference of the displacement input, mm.
pub const X: u32 = 0;
/// Value reference of the force output, N.
pub const FORCE: u32 = 1;
/// Value reference of the tangent output, N/mm.
pub const TANGENT: u32 = 2;
/// Value reference of the energy output (dissipated since the start), mJ.
pub const ENERGY: u32 = 3;
/// Value reference of the temperature input (models with a shift law).
pub const TEMPERATURE: u32 = 4;
/// Value reference of the fault flags output (an Integer).
pub const FAULTS: u32 = 5;
/// Value reference of the refused-step count output (an Integer).
pub const REFUSED: u32 = 6;

/// An FMI base type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `fmi2Real`.
    Real,
    /// `fmi2Integer`.
    Integer,
}

/// One variable of the FMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Variable {
    /// Name.
    pub name: &'static str,
    /// Value reference.
    pub vr: u32,
    /// Base type.
    pub kind: Kind,
    /// An input (else an output).
    pub input: bool,
    /// Unit, as declared in the description's unit definitions.
    pub unit: Option<&'static str>,
    /// What it is.
    pub description: &'static str,
}

/// The variables of an FMU of `model`, in the description's order.
pub fn variables(model: &FmuModel) -> Vec<Variable> {
    let real = |name, vr, input, unit, description| Variable {
        name,
        vr,
        kind: Kind::Real,
        input,
        unit,
        description,
    };
    let mut v = vec![real(
        "x",
        X,
        true,
        Some("mm"),
        "Displacement imposed on the bushing, held over each communication step",
    )];
    if let Some(t) = &model.scene.temperature {
        let unit = match t.law {
            bushing::ShiftFactor::Arrhenius { .. } => Some("K"),
            bushing::ShiftFactor::Wlf { .. } => None,
        };
        v.push(real(
            "temperature",
            TEMPERATURE,
            true,
            unit,
            "Temperature of the part (the unit of the model's shift law): the Maxwell \
             corners move to omega_i / a_T(T) when it changes",
        ));
    }
    v.extend([
        real("force", FORCE, false, Some("N"), "Force of the bushing"),
        real(
            "tangent",
            TANGENT,
            false,
            Some("N/mm"),
            "Algorithmic tangent dF/dx of the last step",
        ),
        real(
            "energy",
            ENERGY,
            false,
            Some("mJ"),
            "Energy dissipated since the start",
        ),
        Variable {
            name: "faults",
            vr: FAULTS,
            kind: Kind::Integer,
            input: false,
            unit: None,
            description: "Fault flags raised so far: 1 non-finite input, 2 input out of range, \
                          4 energy overflow, 8 force out of range",
        },
        Variable {
            name: "refused",
            vr: REFUSED,
            kind: Kind::Integer,
            input: false,
            unit: None,
            description: "Model steps refused so far (their force held)",
        },
    ]);
    v
}

/// `text` as an XML attribute value: the characters XML 1.0 forbids
/// dropped, line breaks made spaces, the markup characters escaped.
fn escape(text: &str) -> String {
    sanitize(text)
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Shortest text that reads back to the same f64.
fn num(v: f64) -> String {
    format!("{v:?}")
}

/// `modelDescription.xml` for `model`, named `name`.
pub fn model_description(model: &FmuModel, name: &str) -> String {
    let scene = &model.scene;
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="{}" guid="{}" description="{}" generationTool="bushing-sim {}" variableNamingConvention="structured" numberOfEventIndicators="0">"#,
        escape(name),
        model.guid,
        escape(&scene.title),
        env!("CARGO_PKG_VERSION"),
    );
    let _ = writeln!(
        s,
        r#"  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" needsExecutionTool="false" canHandleVariableCommunicationStepSize="true" canInterpolateInputs="false" maxOutputDerivativeOrder="0" canRunAsynchronuously="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="false"/>"#
    );
    let variables = variables(model);
    s.push_str("  <UnitDefinitions>\n");
    for (unit, base) in [
        ("mm", r#"m="1" factor="0.001""#),
        ("N", r#"kg="1" m="1" s="-2""#),
        ("N/mm", r#"kg="1" s="-2" factor="1000""#),
        ("mJ", r#"kg="1" m="2" s="-2" factor="0.001""#),
        ("K", r#"K="1""#),
    ] {
        if variables.iter().any(|v| v.unit == Some(unit)) {
            let _ = writeln!(
                s,
                r#"    <Unit name="{}"><BaseUnit {base}/></Unit>"#,
                escape(unit)
            );
        }
    }
    s.push_str("  </UnitDefinitions>\n");
    s.push_str("  <LogCategories>\n");
    for (name, what) in [
        (
            "logStatusWarning",
            "Steps refused by the model (their force held; see the faults output)",
        ),
        (
            "logStatusError",
            "Calls refused: out of order, a step that is not a whole number of model steps, \
             a non-finite input, a bad resource or state",
        ),
        ("logStatusFatal", "An internal failure of the FMU"),
    ] {
        let _ = writeln!(
            s,
            r#"    <Category name="{name}" description="{}"/>"#,
            escape(what)
        );
    }
    s.push_str("  </LogCategories>\n");
    let stop = model
        .stop_time
        .map(|t| format!(r#" stopTime="{}""#, num(t)))
        .unwrap_or_default();
    let _ = writeln!(
        s,
        r#"  <DefaultExperiment startTime="0.0"{stop} stepSize="{}"/>"#,
        num(scene.dt)
    );
    s.push_str("  <ModelVariables>\n");
    for v in &variables {
        let (causality, variability) = match (v.input, v.kind) {
            (true, _) => ("input", "continuous"),
            (false, Kind::Real) => ("output", "continuous"),
            (false, Kind::Integer) => ("output", "discrete"),
        };
        let _ = writeln!(
            s,
            r#"    <ScalarVariable name="{}" valueReference="{}" causality="{causality}" variability="{variability}" description="{}">"#,
            v.name,
            v.vr,
            escape(v.description)
        );
        let unit = v
            .unit
            .map(|u| format!(r#" unit="{}""#, escape(u)))
            .unwrap_or_default();
        let start = match v.vr {
            X => r#" start="0.0""#.to_string(),
            TEMPERATURE => scene
                .temperature
                .as_ref()
                .map(|t| format!(r#" start="{}""#, num(t.at(0.0))))
                .unwrap_or_default(),
            _ => String::new(),
        };
        let tag = match v.kind {
            Kind::Real => "Real",
            Kind::Integer => "Integer",
        };
        let _ = writeln!(s, "      <{tag}{start}{unit}/>");
        s.push_str("    </ScalarVariable>\n");
    }
    s.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    let outputs: Vec<usize> = variables
        .iter()
        .enumerate()
        .filter(|(_, v)| !v.input)
        .map(|(i, _)| i + 1)
        .collect();
    for section in ["Outputs", "InitialUnknowns"] {
        let _ = writeln!(s, "    <{section}>");
        for i in &outputs {
            let _ = writeln!(s, r#"      <Unknown index="{i}"/>"#);
        }
        let _ = writeln!(s, "    </{section}>");
    }
    s.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    s
}
