//! Running a scene: step the bushing over the profile, write the trace and
//! the plots, and measure the cost of the steps alone.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use bushing::Real;

use crate::model::{self, SceneBushing};
use crate::profile;
use crate::scene::{NumberType, Scene};
use crate::svg::{Plot, Series};

/// What a run measured.
#[derive(Debug, Clone)]
pub struct Summary {
    /// Steps taken.
    pub steps: u64,
    /// Effects built, by name.
    pub effects: Vec<String>,
    /// Working type.
    pub number: NumberType,
    /// Wall-clock nanoseconds per step, stepping only (no I/O).
    pub ns_per_step: f64,
    /// Energy dissipated over the run, in mJ (N·mm).
    pub dissipated_mj: f64,
    /// Largest |force| in N.
    pub peak_force: f64,
    /// Steps refused for non-finite or out-of-range input.
    pub refused: u32,
    /// Files written.
    pub files: Vec<PathBuf>,
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "steps          {}", self.steps)?;
        let effects = if self.effects.is_empty() {
            "none (backbone only)".to_string()
        } else {
            self.effects.join(", ")
        };
        writeln!(f, "effects        {effects}")?;
        writeln!(f, "number type    {}", self.number.name())?;
        writeln!(
            f,
            "cost           {:.1} ns/step (host wall clock, stepping only)",
            self.ns_per_step
        )?;
        writeln!(f, "dissipated     {:.6e} mJ", self.dissipated_mj)?;
        writeln!(f, "peak |force|   {:.6e} N", self.peak_force)?;
        writeln!(f, "refused steps  {}", self.refused)?;
        for file in &self.files {
            writeln!(f, "wrote          {}", file.display())?;
        }
        Ok(())
    }
}

/// Runs `scene`, writing `trace.csv` and the plots into `out`.
pub fn run(scene: &Scene, out: &Path) -> Result<Summary, String> {
    match scene.number {
        NumberType::F32 => run_typed::<f32>(scene, out),
        NumberType::F64 => run_typed::<f64>(scene, out),
    }
}

/// Points kept for the plots.
const PLOT_POINTS: u64 = 20_000;
/// Steps per timed chunk.
const CHUNK: usize = 4096;

fn run_typed<T: Real>(scene: &Scene, out: &Path) -> Result<Summary, String> {
    let bushing: SceneBushing<T> = model::build(scene).map_err(|e| e.to_string())?;
    fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let trace_path = out.join("trace.csv");
    let file =
        fs::File::create(&trace_path).map_err(|e| format!("{}: {e}", trace_path.display()))?;
    let mut csv = BufWriter::new(file);
    let names = model::effect_names(scene);
    let mut header = String::from("time_s,x_mm,force_N,elastic_N");
    for n in &names {
        header.push_str(&format!(",{}_N", n.replace([' ', ','], "_")));
    }
    header.push_str(",dissipated_mJ");
    writeln!(csv, "{header}").map_err(|e| e.to_string())?;

    let steps = scene.steps();
    let stride = steps.div_ceil(PLOT_POINTS).max(1);
    let mut loop_points = Vec::new();
    let mut elastic_points = Vec::new();
    let x0 = profile::displacement(&scene.profile, 0.0);
    let mut state = bushing.state_at(T::from_f64(x0));
    let mut inputs = Vec::with_capacity(CHUNK);
    let mut outputs = Vec::with_capacity(CHUNK);
    let mut busy = 0.0f64;
    let mut energy = 0.0f64;
    let mut peak = 0.0f64;
    let mut n = 0u64;
    while n < steps {
        let len = (steps - n).min(CHUNK as u64) as usize;
        inputs.clear();
        for k in 0..len as u64 {
            let t = (n + 1 + k) as f64 * scene.dt;
            inputs.push(T::from_f64(profile::displacement(&scene.profile, t)));
        }
        outputs.clear();
        let start = Instant::now();
        for &x in &inputs {
            outputs.push(bushing.step(&mut state, x));
        }
        busy += start.elapsed().as_secs_f64();
        let mut line = String::new();
        for (k, (x, o)) in inputs.iter().zip(&outputs).enumerate() {
            let i = n + 1 + k as u64;
            let t = i as f64 * scene.dt;
            energy += o.dissipated.to_f64();
            let f = o.force.to_f64();
            peak = peak.max(f.abs());
            line.clear();
            line.push_str(&format!(
                "{t:.9},{:e},{f:e},{:e}",
                x.to_f64(),
                o.elastic.to_f64()
            ));
            match &o.effects {
                Some(r) => {
                    for e in model::effect_outputs::<T>(scene, r) {
                        line.push_str(&format!(",{:e}", e.force.to_f64()));
                    }
                }
                None => names.iter().for_each(|_| line.push_str(",nan")),
            }
            line.push_str(&format!(",{energy:e}"));
            writeln!(csv, "{line}").map_err(|e| e.to_string())?;
            if i.is_multiple_of(stride) {
                loop_points.push((x.to_f64(), f));
                elastic_points.push((x.to_f64(), o.elastic.to_f64()));
            }
        }
        n += len as u64;
    }
    csv.flush().map_err(|e| e.to_string())?;

    let effects = if names.is_empty() {
        "backbone only".to_string()
    } else {
        names.join(" + ")
    };
    let plot = Plot {
        title: if scene.title.is_empty() {
            format!("Force-displacement ({effects})")
        } else {
            scene.title.clone()
        },
        x_label: "displacement x [mm]".into(),
        y_label: "force F [N]".into(),
        series: vec![
            Series {
                name: format!("total force, {effects}, {}", scene.number.name()),
                points: loop_points,
            },
            Series {
                name: "long-term elastic branch g0 F_inf(x)".into(),
                points: elastic_points,
            },
        ],
    };
    let loop_path = out.join("force-displacement.svg");
    fs::write(&loop_path, plot.render()).map_err(|e| format!("{}: {e}", loop_path.display()))?;
    Ok(Summary {
        steps,
        effects: names,
        number: scene.number,
        ns_per_step: busy * 1e9 / steps.max(1) as f64,
        dissipated_mj: energy,
        peak_force: peak,
        refused: state.rejected(),
        files: vec![trace_path, loop_path],
    })
}
