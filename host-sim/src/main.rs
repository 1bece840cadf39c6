//! `bushing-sim`: run scenes and regenerate reports.

use std::path::PathBuf;
use std::process::ExitCode;

use bushing_sim::{Scene, iwan_report, modulus, run, xf_report};

const USAGE: &str = "\
usage:
  bushing-sim run SCENE.toml --out DIR     simulate a scene: DIR/trace.csv, DIR/*.svg
  bushing-sim maxwell-table [--out FILE]   complex-modulus error of every Maxwell form
  bushing-sim xf-table [--out FILE]        saturation of the x_f cell forms against the step
  bushing-sim iwan-table [--out FILE]      Iwan discretisations of the STS and Segalman laws
  bushing-sim help";

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

fn dispatch(args: &[String]) -> Result<(), String> {
    let words: Vec<&str> = args.iter().map(String::as_str).collect();
    match words.as_slice() {
        ["run", scene, "--out", out] | ["run", "--out", out, scene] => {
            let scene = Scene::load(&PathBuf::from(scene)).map_err(|e| e.to_string())?;
            let summary = run::run(&scene, &PathBuf::from(out))?;
            print!("{summary}");
            Ok(())
        }
        ["maxwell-table"] => {
            print!("{}", modulus::table());
            Ok(())
        }
        ["maxwell-table", "--out", file] => {
            std::fs::write(file, modulus::table()).map_err(|e| format!("{file}: {e}"))?;
            println!("wrote {file}");
            Ok(())
        }
        ["iwan-table"] => {
            print!("{}", iwan_report::table());
            Ok(())
        }
        ["iwan-table", "--out", file] => {
            std::fs::write(file, iwan_report::table()).map_err(|e| format!("{file}: {e}"))?;
            println!("wrote {file}");
            Ok(())
        }
        ["xf-table"] => {
            print!("{}", xf_report::table());
            Ok(())
        }
        ["xf-table", "--out", file] => {
            std::fs::write(file, xf_report::table()).map_err(|e| format!("{file}: {e}"))?;
            println!("wrote {file}");
            Ok(())
        }
        ["help"] | ["--help"] | ["-h"] => {
            println!("{USAGE}");
            Ok(())
        }
        _ => Err(format!("unrecognised arguments {args:?}\n{USAGE}")),
    }
}
