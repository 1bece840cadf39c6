//! `bushing-sim`: run scenes and regenerate reports.

use std::path::PathBuf;
use std::process::ExitCode;

use bushing_sim::scene::NumberType;
use bushing_sim::{
    Scene, accuracy_cost, compare, cost, fractional_report, iwan_report, modulus, powertrain, run,
    validate, xf_report,
};

const USAGE: &str = "\
usage:
  bushing-sim run SCENE.toml --out DIR [--number f32|f64]
                                           simulate a scene: DIR/trace.csv, DIR/modulus.csv, DIR/*.svg
                                           (--number overrides the scene's run.number)
  bushing-sim validate SCENE.toml          compare a scene with its closed-form references
  bushing-sim cost SCENE.toml              ns per step of the scene against the sum of its parts
  bushing-sim cost --instructions SCENE.toml   the same in host instructions (valgrind's callgrind)
  bushing-sim maxwell-table [--out FILE]   complex-modulus error of every Maxwell form
  bushing-sim xf-table [--out FILE]        saturation of the x_f cell forms against the step
  bushing-sim iwan-table [--out FILE]      Iwan discretisations of the STS and Segalman laws
  bushing-sim fractional-table [--out FILE]  Grünwald accuracy, Maxwell fits and their cost
  bushing-sim powertrain --out DIR          the engine on three 6-DOF mounts (seed 000 §5.2): modes against
                                           Table 5.2, stop/start transient with viscous and STS mounts
  bushing-sim compare-trace HOST_TRACE.csv FIRMWARE.log [--within N]
                                           a firmware's logged forces against a host trace (trace_every = 1):
                                           bit-identical, or within N newtons
  bushing-sim accuracy-cost [--quick] --kernels FILE... --elf TRIPLE=PATH... [--peers FILE...] --out DIR
                                           error against cost of every kernel (docs/accuracy-cost.md)
  bushing-sim help";

/// Steps per part for `cost --instructions`.
const INSTRUCTION_STEPS: usize = 200_000;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match dispatch(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}

/// The generated reports, by command name.
fn report(name: &str) -> Option<fn() -> String> {
    match name {
        "maxwell-table" => Some(modulus::table),
        "xf-table" => Some(xf_report::table),
        "iwan-table" => Some(iwan_report::table),
        "fractional-table" => Some(fractional_report::table),
        _ => None,
    }
}

fn load(scene: &str) -> Result<Scene, String> {
    Scene::load(&PathBuf::from(scene)).map_err(|e| e.to_string())
}

fn dispatch(args: &[String]) -> Result<(), String> {
    let words: Vec<&str> = args.iter().map(String::as_str).collect();
    match words.as_slice() {
        ["run", rest @ ..] => {
            let (scene, out, number) = run_args(rest)?;
            let scene = Scene::load_as(&PathBuf::from(scene), number).map_err(|e| e.to_string())?;
            let options = run::Options { progress: true };
            let summary = run::run_with(&scene, &PathBuf::from(out), options)?;
            print!("{summary}");
            Ok(())
        }
        ["validate", scene] => {
            let scene = load(scene)?;
            print!("{}", validate::validate(&scene)?);
            Ok(())
        }
        ["cost", scene] => {
            let scene = load(scene)?;
            print!("{}", cost::cost(&scene).map_err(|e| e.to_string())?);
            Ok(())
        }
        ["cost", "--instructions", file] | ["cost", file, "--instructions"] => {
            let scene = load(file)?;
            let report = cost::cost_instructions(&PathBuf::from(file), &scene, INSTRUCTION_STEPS)
                .map_err(|e| e.to_string())?;
            print!("{report}");
            Ok(())
        }
        ["cost-part", file, part, steps] => {
            let scene = load(file)?;
            let number = |s: &str| s.parse::<usize>().map_err(|e| format!("{s}: {e}"));
            cost::run_part(&scene, number(part)?, number(steps)?).map_err(|e| e.to_string())
        }
        [name] | [name, "--out", _] if report(name).is_some() => {
            let text = report(name).map(|f| f()).unwrap_or_default();
            match words.as_slice() {
                [_, "--out", file] => {
                    std::fs::write(file, text).map_err(|e| format!("{file}: {e}"))?;
                    println!("wrote {file}");
                }
                _ => print!("{text}"),
            }
            Ok(())
        }
        ["powertrain", "--out", dir] => {
            print!("{}", powertrain::report(&PathBuf::from(dir))?);
            Ok(())
        }
        ["compare-trace", rest @ ..] => {
            let c = compare::cli(rest)?;
            print!("{c}");
            match c.first_mismatch {
                None => Ok(()),
                Some(m) => Err(format!("firmware and host differ at {m}")),
            }
        }
        ["accuracy-cost", rest @ ..] => {
            print!("{}", accuracy_cost::cli(rest).map_err(|e| e.to_string())?);
            Ok(())
        }
        ["accuracy-cost-part", calls] => {
            let calls = calls
                .parse::<usize>()
                .map_err(|e| format!("{calls}: {e}"))?;
            accuracy_cost::host::run_part(calls).map_err(|e| e.to_string())
        }
        ["help"] | ["--help"] | ["-h"] => {
            println!("{USAGE}");
            Ok(())
        }
        _ => Err(format!("unrecognised arguments {args:?}\n{USAGE}")),
    }
}

/// The arguments of `run`, in any order: the scene, `--out DIR` and an
/// optional `--number f32|f64`.
fn run_args<'a>(args: &[&'a str]) -> Result<(&'a str, &'a str, Option<NumberType>), String> {
    let (mut scene, mut out, mut number) = (None, None, None);
    let mut it = args.iter().copied();
    while let Some(a) = it.next() {
        let slot = match a {
            "--out" => &mut out,
            "--number" => &mut number,
            _ if a.starts_with("--") => return Err(format!("run: unknown option {a}\n{USAGE}")),
            _ => &mut scene,
        };
        let value = if a.starts_with("--") {
            it.next()
                .ok_or_else(|| format!("run: {a} needs a value\n{USAGE}"))?
        } else {
            a
        };
        if slot.replace(value).is_some() {
            let what = if a.starts_with("--") { a } else { "SCENE.toml" };
            return Err(format!("run: {what} given twice\n{USAGE}"));
        }
    }
    let number = match number {
        None => None,
        Some("f32") => Some(NumberType::F32),
        Some("f64") => Some(NumberType::F64),
        Some(other) => {
            return Err(format!("run: --number '{other}' is not one of f32, f64"));
        }
    };
    match (scene, out) {
        (Some(scene), Some(out)) => Ok((scene, out, number)),
        _ => Err(format!(
            "run takes SCENE.toml --out DIR [--number f32|f64]\n{USAGE}"
        )),
    }
}
