//! `bushing-sim`: run scenes and regenerate reports.

use std::path::PathBuf;
use std::process::ExitCode;

use bushing_sim::{
    Scene, accuracy_cost, cost, fractional_report, iwan_report, modulus, run, validate, xf_report,
};

const USAGE: &str = "\
usage:
  bushing-sim run SCENE.toml --out DIR     simulate a scene: DIR/trace.csv, DIR/modulus.csv, DIR/*.svg
  bushing-sim validate SCENE.toml          compare a scene with its closed-form references
  bushing-sim cost SCENE.toml              ns per step of the scene against the sum of its parts
  bushing-sim cost --instructions SCENE.toml   the same in host instructions (valgrind's callgrind)
  bushing-sim maxwell-table [--out FILE]   complex-modulus error of every Maxwell form
  bushing-sim xf-table [--out FILE]        saturation of the x_f cell forms against the step
  bushing-sim iwan-table [--out FILE]      Iwan discretisations of the STS and Segalman laws
  bushing-sim fractional-table [--out FILE]  Grünwald accuracy, Maxwell fits and their cost
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
        ["run", scene, "--out", out] | ["run", "--out", out, scene] => {
            let scene = load(scene)?;
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
            print!("{}", cost::cost(&scene)?);
            Ok(())
        }
        ["cost", "--instructions", file] | ["cost", file, "--instructions"] => {
            let scene = load(file)?;
            let report = cost::cost_instructions(&PathBuf::from(file), &scene, INSTRUCTION_STEPS)?;
            print!("{report}");
            Ok(())
        }
        ["cost-part", file, part, steps] => {
            let scene = load(file)?;
            let number = |s: &str| s.parse::<usize>().map_err(|e| format!("{s}: {e}"));
            cost::run_part(&scene, number(part)?, number(steps)?)
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
        ["accuracy-cost", rest @ ..] => {
            print!("{}", accuracy_cost::cli(rest)?);
            Ok(())
        }
        ["accuracy-cost-part", calls] => {
            let calls = calls
                .parse::<usize>()
                .map_err(|e| format!("{calls}: {e}"))?;
            accuracy_cost::host::run_part(calls)
        }
        ["help"] | ["--help"] | ["-h"] => {
            println!("{USAGE}");
            Ok(())
        }
        _ => Err(format!("unrecognised arguments {args:?}\n{USAGE}")),
    }
}
