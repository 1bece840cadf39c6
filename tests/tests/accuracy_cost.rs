//! The accuracy-cost report generator in quick mode on a small fixed
//! sample of firmware output: structure only (CSV columns, every family,
//! a well-formed plot, non-dominated Pareto fronts, the targets and the
//! tables), never a timing.

use std::sync::OnceLock;

use bushing_sim::accuracy_cost::{self, CSV_COLUMNS, Inputs, Options, Report};
use bushing_sim::plot;

/// A few lines as `kernel-cost` prints them (M4F and M3), one of a family
/// the generator does not know, and a comment.
const KERNELS_M4F: &str = "\
# kernel cost, 2000 calls each, sine 2 mm over 100 samples, dt = 0.0005 s
kernel target=m4f type=f32 family=maxwell name=rate-exact-ramp/plain n=8 per_call=120.0 net=112.0 state_bytes=32 params_bytes=448 fn=0x000019a4
kernel target=m4f type=f32 family=maxwell name=rate-exact-ramp/plain n=1 per_call=39.0 net=30.9 state_bytes=4 params_bytes=80 fn=0x00002c74
kernel target=m4f type=f32 family=maxwell name=rate-midpoint/plain n=4 per_call=68.0 net=60.0 state_bytes=16 params_bytes=240 fn=0x00000c6c calls=10 windows=0,1,2
kernel target=m4f type=f32 family=maxwell name=load-explicit/plain n=16 per_call=331.0 net=323.0 state_bytes=64 params_bytes=864 fn=0x00001d9c
kernel target=m4f type=f32 family=maxwell-force name=rate-exact-ramp/plain n=8 per_call=71.0 net=69.9 state_bytes=32 params_bytes=448 fn=0x00007a5c
kernel target=m4f type=f32 family=maxwell-force name=rate-exact-ramp/multiplied n=8 per_call=65.0 net=64.0 state_bytes=32 params_bytes=448 fn=0x00006ce0
kernel target=m4f type=f32 family=iwan name=clamp/log n=16 input=sine per_call=155.6 net=147.6 state_bytes=72 params_bytes=264 fn=0x000008a0
kernel target=m4f type=f32 family=iwan name=clamp/log n=16 input=small-sine per_call=472.0 net=465.0 state_bytes=72 params_bytes=264 fn=0x000008a0
kernel target=m4f type=f32 family=iwan name=clamp/log n=16 input=noise per_call=288.0 net=281.0 state_bytes=72 params_bytes=264 fn=0x000008a0
kernel target=m4f type=f32 family=iwan name=clamp/log n=4 per_call=94.2 net=86.2 state_bytes=24 params_bytes=72 fn=0x00003398
kernel target=m4f type=f32 family=xf name=midpoint n=1 per_call=138.1 net=131.1 state_bytes=4 params_bytes=40 fn=0x00002778
kernel target=m4f type=f32 family=xf name=exact-ramp n=1 per_call=147.4 net=140.4 state_bytes=4 params_bytes=40 fn=0x00002778
kernel target=m4f type=f32 family=backbone name=polynomial-4 n=1 per_call=55.0 net=48.0 state_bytes=24 params_bytes=56 fn=0x00005ab0
kernel target=m4f type=f32 family=bushing name=default/spline+4maxwell+3jenkins n=7 per_call=206.5 net=199.5 state_bytes=60 params_bytes=568 fn=0x00003b40
kernel target=m4f type=f32 family=grunwald name=bushing/alpha-0.5 n=64 per_call=413.7 net=406.7 state_bytes=288 params_bytes=368 fn=0x000048b0
kernel target=m4f type=f32 family=tracker name=ekf/1-mode-1-acc n=4 per_call=1388.1 net=1388.1 state_bytes=100 params_bytes=216 fn=0x00007f10
kernel target=m4f type=f32 family=tracker name=ukf/1-mode-1-acc n=4 per_call=4314.4 net=4314.3 state_bytes=100 params_bytes=216 fn=0x00007f10
kernel target=m4f type=f32 family=retune name=retune-8/libm n=8 per_call=1211.0 net=1211.0 state_bytes=0 params_bytes=448 fn=0x00000000
kernel target=m4f type=f32 family=retune name=retune-8/micromath n=8 per_call=1147.4 net=1147.4 state_bytes=0 params_bytes=448 fn=0x00000000
kernel target=m4f type=fixed family=mount6 name=six-axis n=6 per_call=900.0 state_bytes=200 params_bytes=1000 fn=0x0
";

const KERNELS_M3: &str = "\
kernel target=m3 type=f32 family=maxwell name=rate-exact-ramp/plain n=8 per_call=2500.0 net=2490.0 state_bytes=32 params_bytes=448 fn=0x00001000
kernel target=m3 type=f32 family=tracker name=ekf/1-mode-1-acc n=4 per_call=21771.5 net=21771.5 state_bytes=100 params_bytes=216 fn=0x0000d070
";

/// The M4F target built for the Cortex-M7: its lines say `target=m7`.
const KERNELS_M7: &str = "\
kernel target=m7 type=f32 family=maxwell name=rate-exact-ramp/plain n=8 per_call=70.0 net=61.0 state_bytes=32 params_bytes=448 fn=0x00001000
";

const PEERS: &str = "\
kalman name=bushing-ekf crate=bushing filter=ekf cost=1388 unit=instructions freq_err_pct=0.004 damp_err_pts=0.002 amp_rms=0.01
kalman name=peer-ekf crate=some-kalman@0.3.1 filter=ekf cost=5000 unit=instructions freq_err_pct=0.004 damp_err_pts=0.003 amp_rms=0.02
";

/// The executed-instruction mix of three windows: the kernel (a loop of
/// 5 instructions run 10 times), its empty stand-in and the baseline.
const MIX_M4F: &str = "\
qemu-mix 1 open=0x00000400 close=0x00000408
window 0 insns=50 blocks=1
tb 0x00000100 0x00000110 5 10 9
window 1 insns=20 blocks=1
tb 0x00000200 0x00000204 2 10 10
window 2 insns=10 blocks=1
tb 0x00000300 0x00000302 1 10 10
end windows=3
";

/// The disassembly the mix runs through, as llvm-objdump prints it.
const DISASSEMBLY_M4F: &str = "
00000100 <kernel>:
     100:      \tvldr\ts0, [r0]
     104:      \tvmla.f32\ts1, s0, s2
     108:      \tvmla.f32\ts1, s3, s4
     10c:      \tsubs\tr0, #0x1
     10e:      \tbne\t0x100 <kernel>
00000200 <empty>:
     200:      \tnop
     202:      \tbx\tlr
00000300 <baseline>:
     300:      \tb\t0x300 <baseline>
";

fn inputs() -> Inputs {
    Inputs {
        mixes: vec![accuracy_cost::MixInput {
            triple: "thumbv7em-none-eabihf".into(),
            source: "mix.txt".into(),
            mix: MIX_M4F.into(),
            disassembly: DISASSEMBLY_M4F.into(),
        }],
        kernels: vec![
            ("m4f.txt".into(), KERNELS_M4F.into()),
            ("m3.txt".into(), KERNELS_M3.into()),
            ("m7.txt".into(), KERNELS_M7.into()),
        ],
        elfs: Vec::new(),
        peers: vec![("peers.txt".into(), PEERS.into())],
        peers_mix: None,
        llvm_mca: None,
        other_build: None,
        headline_build: None,
    }
}

/// The quick report of the sample, generated once for every test.
fn quick() -> &'static Report {
    static REPORT: OnceLock<Report> = OnceLock::new();
    REPORT.get_or_init(|| {
        accuracy_cost::generate(&inputs(), &Options::quick()).expect("the generator runs")
    })
}

/// Splits one CSV line, honouring double quotes.
fn csv_fields(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                if let Some(f) = out.last_mut() {
                    f.push('"');
                }
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(String::new()),
            c => {
                if let Some(f) = out.last_mut() {
                    f.push(c);
                }
            }
        }
    }
    out
}

#[test]
fn quick_report_has_every_part() {
    let report = quick();

    // CSV: the columns, one row per configuration, every family.
    let mut lines = report.csv.lines();
    assert_eq!(lines.next(), Some(CSV_COLUMNS.join(",").as_str()));
    let rows: Vec<Vec<String>> = lines.map(csv_fields).collect();
    assert!(rows.len() >= report.rows.len());
    for r in &rows {
        assert_eq!(r.len(), CSV_COLUMNS.len(), "{r:?}");
    }
    for family in [
        "maxwell",
        "maxwell-force",
        "grunwald",
        "fractional-fit",
        "iwan-sts",
        "iwan-segalman",
        "xf",
        "tracker",
        "retune",
        "backbone",
        "bushing",
        "sts",
        "iwan",
        "mount6",
    ] {
        assert!(
            rows.iter().any(|r| r[0] == family),
            "family {family} missing from the CSV"
        );
    }
    // Maxwell: every form, state, order and number type.
    let maxwell = rows.iter().filter(|r| r[0] == "maxwell").count();
    assert_eq!(maxwell, 5 * 3 * 5 * 3);
    for number in ["f32", "f64", "fixed"] {
        assert!(rows.iter().any(|r| r[0] == "maxwell" && r[3] == number));
    }
    // Errors are numbers where there is a reference; the joined M4F figure
    // is the net one.
    let joined = rows
        .iter()
        .find(|r| {
            r[0] == "maxwell" && r[1] == "rate-exact-ramp/plain" && r[2] == "8" && r[3] == "f32"
        })
        .expect("the 8-cell exact-ramp row");
    let col = |name: &str| {
        let i = CSV_COLUMNS.iter().position(|c| *c == name);
        joined[i.expect("a CSV column")].as_str()
    };
    assert!(
        col("error")
            .parse::<f64>()
            .is_ok_and(|e| e > 0.0 && e < 0.01)
    );
    assert_eq!(col("m4f_instr"), "112");
    assert_eq!(col("m3_instr"), "2490");
    assert_eq!(col("m7_instr"), "61");
    assert_eq!(col("state_bytes"), "32");

    // The plot.
    plot::well_formed(&report.svg).expect("well-formed SVG");
    assert!(report.svg.contains("maxwell ("));

    // Markdown: targets, cheapest within 1 %, tables, other kernels, peers.
    let md = &report.markdown;
    for part in [
        "## Targets",
        "## Cheapest configuration within 1 % error",
        "## Error against cost",
        "## Families",
        "## Firmware footprint",
        "## Other kernels",
        "## Tracker against peer crates",
        "mount6",
        "some-kalman@0.3.1",
    ] {
        assert!(md.contains(part), "{part} missing from the report");
    }
    assert!(md.contains("**NOT met**") && md.contains("| met |"));
    assert!(report.other.iter().any(|l| l.family == "mount6"));
}

#[test]
fn pareto_fronts_are_not_dominated() {
    let report = quick();
    let on_plot = |r: &&accuracy_cost::Row| r.error.is_some() && r.m4f.is_some();
    let mut fronts = 0;
    for p in report.rows.iter().filter(|r| r.front) {
        fronts += 1;
        let family = || report.rows.iter().filter(|q| q.key.family == p.key.family);
        let cycles = accuracy_cost::ranked_by_cycles(family());
        let cost = |r: &accuracy_cost::Row| accuracy_cost::rank_cost(r, cycles).unwrap_or(f64::NAN);
        let (pe, pc) = (p.error.unwrap_or(f64::NAN), cost(p));
        for q in family().filter(on_plot) {
            let (qe, qc) = (q.error.unwrap_or(f64::NAN), cost(q));
            if qc < pc {
                assert!(
                    pe < qe,
                    "{:?} on the front but {:?} is cheaper and as accurate",
                    p.key,
                    q.key
                );
            }
        }
    }
    assert!(fronts > 0);
    // Only rows with an error and an M4F figure are on a front.
    assert!(report.rows.iter().filter(|r| r.front).all(|r| on_plot(&r)));
}

#[test]
fn targets_are_judged_from_the_firmware_lines() {
    let report = quick();
    let goal = |what: &str| {
        report
            .goals
            .iter()
            .find(|g| g.what.contains(what))
            .unwrap_or_else(|| panic!("no target {what}"))
    };
    let slow = goal("slow-exact");
    assert!((slow.measured.unwrap_or(0.0) - 69.9 / 8.0).abs() < 1e-9);
    assert!(slow.met());
    assert!(goal("multiplicative").met());
    // Judged on its worst input: 465 / 16 instructions a cell.
    let iwan = goal("clamp Iwan");
    assert_eq!(iwan.measured, Some(465.0 / 16.0));
    assert!(!iwan.met() && iwan.note.contains("worst input small-sine"));
    assert!(goal("default 1D bushing").met());
    assert!(!goal("EKF").met());
    assert!(!goal("UKF").met());
    // 1388 against 5000 at equal or better accuracy: 0.28 <= 1/3.
    let third = goal("1/3");
    assert!(third.met(), "{third:?}");
}

#[test]
fn estimated_cycles_come_from_the_instruction_mix() {
    let report = quick();
    let row = report
        .rows
        .iter()
        .find(|r| {
            r.key.family == "maxwell"
                && r.key.name == "rate-midpoint/plain"
                && r.key.n == 4
                && r.key.number == "f32"
        })
        .expect("the mixed row");
    // Kernel window: (vldr 2 + vmla 3 + vmla 3 with its accumulator just
    // written, +1 + subs 1 + bne 1) x 10 + 9 taken x 2 = 128; empty: (1 +
    // 1) x 10 + 10 x 2 = 40; baseline: 1 x 10 + 10 x 2 = 30.
    assert_eq!(row.m4f_cycles, Some((128.0 - 40.0) / 10.0));
    // The instructions become the mix's exact counts: (50 - 20) / 10.
    assert_eq!(row.m4f, Some(3.0));
    // A row without windows has no estimate, and the family is then
    // ranked by instructions.
    let other = report
        .rows
        .iter()
        .find(|r| r.key.family == "maxwell" && r.key.n == 8 && r.key.number == "f32")
        .expect("an unmixed row");
    assert_eq!(other.m4f_cycles, None);
    assert!(!accuracy_cost::ranked_by_cycles(
        report.rows.iter().filter(|r| r.key.family == "maxwell")
    ));
    assert!(report.markdown.contains("M4F cycles"));
    // No llvm-mca given: the cross-check says it did not run.
    assert!(
        report
            .markdown
            .contains("## Cycle model against llvm-mca\n")
    );
    assert!(report.markdown.contains("Not run: no `--llvm-mca PROGRAM`"));
}

#[test]
fn a_kernel_on_several_inputs_is_costed_on_its_worst() {
    let report = quick();
    let row = report
        .rows
        .iter()
        .find(|r| r.key.family == "iwan" && r.key.name == "clamp/log" && r.key.n == 16)
        .expect("the 16-cell clamp bank");
    assert_eq!(row.m4f, Some(465.0));
    assert_eq!(row.m4f_input.as_deref(), Some("small-sine"));
    let md = &report.markdown;
    assert!(md.contains("## Cost by input"));
    // The row of the input table: each input, the worst and its ratio to
    // the first input.
    let line = md
        .lines()
        .find(|l| l.starts_with("| iwan: clamp/log | 16 | - ("))
        .expect("the bank in the input table");
    assert!(
        line.contains("- (148)") && line.contains("- (465)") && line.contains("- (281)"),
        "{line}"
    );
    assert!(line.contains("small-sine | 3.15 |"), "{line}");
    // The same kernel twice on one input is still a duplicate.
    let mut again = inputs();
    again.kernels.push((
        "again.txt".into(),
        "kernel target=m4f type=f32 family=iwan name=clamp/log n=16 input=noise per_call=1 net=1\n"
            .into(),
    ));
    let e = accuracy_cost::generate(&again, &Options::quick())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("again.txt:1"), "{e}");
}

#[test]
fn another_build_is_compared_on_estimated_cycles() {
    let mut i = inputs();
    // The other build: the same instructions but plain adds for the
    // multiply-accumulates (2 cycles less each, and no stall).
    i.other_build = Some(accuracy_cost::OtherBuild {
        name: "adds".into(),
        kernels: ("other.txt".into(), KERNELS_M4F.into()),
        mix: accuracy_cost::MixInput {
            triple: "thumbv7em-none-eabihf".into(),
            source: "other-mix.txt".into(),
            mix: MIX_M4F.into(),
            disassembly: DISASSEMBLY_M4F.replace("vmla.f32", "vadd.f32"),
        },
    });
    let report = accuracy_cost::generate(&i, &Options::quick()).expect("the generator runs");
    let md = &report.markdown;
    // Kernel window 128 against (2 + 1 + 1 + 1 + 1) x 10 + 18 = 78 in the
    // other; stand-ins 40 in both: (128 - 40) / (78 - 40) = 2.316.
    assert!(
        md.contains("Against `adds`, over the 1 M4F f32 kernels")
            && md.contains("cycles 2.316 times"),
        "{}",
        md.lines().find(|l| l.starts_with("Against")).unwrap_or("")
    );
    assert!(quick().markdown.contains("Not compared in this run"));
}

#[test]
fn the_harness_spread_between_two_binaries_is_stated() {
    let mut i = inputs();
    // The same kernel in a binary of its own: the same mix (spread 0),
    // then a kernel window of 10 more instructions over 10 calls (the
    // loop of 5 twice more): 1 more a call.
    let alone = |mix: &str| accuracy_cost::OtherBuild {
        name: "headline-only".into(),
        kernels: ("alone.txt".into(), KERNELS_M4F.into()),
        mix: accuracy_cost::MixInput {
            triple: "thumbv7em-none-eabihf".into(),
            source: "alone-mix.txt".into(),
            mix: mix.into(),
            disassembly: DISASSEMBLY_M4F.into(),
        },
    };
    i.headline_build = Some(alone(MIX_M4F));
    let report = accuracy_cost::generate(&i, &Options::quick()).expect("the generator runs");
    let stated = |md: &str| {
        md.lines()
            .find(|l| l.starts_with("Against the `headline-only` binary"))
            .unwrap_or("")
            .to_string()
    };
    let line = stated(&report.markdown);
    assert!(
        line.contains("M4F kernel and input pairs measured in both")
            && line.contains("largest difference is 0.0 instructions and 0.0 estimated cycles"),
        "{line}"
    );
    let longer = MIX_M4F.replace(
        "window 0 insns=50 blocks=1\ntb 0x00000100 0x00000110 5 10 9",
        "window 0 insns=60 blocks=1\ntb 0x00000100 0x00000110 5 12 11",
    );
    assert_ne!(longer, MIX_M4F, "the sample's kernel window");
    i.headline_build = Some(alone(&longer));
    let report = accuracy_cost::generate(&i, &Options::quick()).expect("the generator runs");
    let line = stated(&report.markdown);
    assert!(
        line.contains("largest difference is 1.0 instructions"),
        "{line}"
    );
    assert!(
        quick()
            .markdown
            .contains("Not compared in this run (`scripts/accuracy-cost.sh` builds")
    );
}

#[test]
fn peers_measured_with_the_plugin_get_exact_counts_and_cycles() {
    let mut i = inputs();
    // A peer whose pass is window 0 of the sample mix and whose stand-in
    // is window 1: (50 - 20) / 10 = 3 instructions and (128 - 40) / 10 =
    // 8.8 estimated cycles an update, whatever its printed cost.
    i.peers = vec![(
        "peers-m4f.txt".into(),
        "kalman name=peer-ekf crate=some-kalman@0.3.1 filter=ekf cost=40 unit=instructions \
         freq_err_pct=0.004 damp_err_pts=0.003 amp_rms=0.02 calls=10 windows=0,1\n"
            .into(),
    )];
    i.peers_mix = Some(accuracy_cost::MixInput {
        triple: "thumbv7em-none-eabihf".into(),
        source: "peers-mix.txt".into(),
        mix: MIX_M4F.into(),
        disassembly: DISASSEMBLY_M4F.into(),
    });
    let report = accuracy_cost::generate(&i, &Options::quick()).expect("the generator runs");
    let row = report
        .markdown
        .lines()
        .find(|l| l.starts_with("| peers-m4f.txt | peer-ekf"))
        .unwrap_or("");
    assert!(
        row.contains("| 3.00 | instructions |") && row.contains("| 8.80 |"),
        "{row}"
    );
    // A window the mix does not have is an error, not a silent figure.
    i.peers[0].1 = i.peers[0].1.replace("windows=0,1", "windows=0,7");
    let e = accuracy_cost::generate(&i, &Options::quick())
        .map(|_| ())
        .unwrap_err();
    assert!(e.to_string().contains("peers-mix.txt"), "{e}");
}

#[test]
fn broken_mixes_are_named_errors() {
    let with_mix = |mix: &str, dis: &str| {
        let mut i = inputs();
        i.mixes[0].mix = mix.into();
        i.mixes[0].disassembly = dis.into();
        accuracy_cost::generate(&i, &Options::quick())
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    // A run that did not finish.
    let e = with_mix(&MIX_M4F.replace("end windows=3\n", ""), DISASSEMBLY_M4F);
    assert!(e.contains("mix.txt") && e.contains("no 'end' line"), "{e}");
    // A window the line names but the mix lacks.
    let short = MIX_M4F
        .replace(
            "window 2 insns=10 blocks=1\ntb 0x00000300 0x00000302 1 10 10\n",
            "",
        )
        .replace("windows=3", "windows=2");
    let e = with_mix(&short, DISASSEMBLY_M4F);
    assert!(e.contains("no window 2"), "{e}");
    // A disassembly of another build.
    let e = with_mix(MIX_M4F, &DISASSEMBLY_M4F.replace("     100:", "      f0:"));
    assert!(e.contains("0x100"), "{e}");
    // A garbled line, by number.
    let e = with_mix(
        &MIX_M4F.replace("tb 0x00000200", "tb 0x0000020z"),
        DISASSEMBLY_M4F,
    );
    assert!(e.contains("mix.txt:5"), "{e}");
}

#[test]
fn bad_firmware_lines_are_named_errors() {
    let mut bad = inputs();
    bad.kernels.push((
        "broken.txt".into(),
        "kernel target=m4f type=f32 family=maxwell name=x n=eight per_call=1\n".into(),
    ));
    let e = accuracy_cost::generate(&bad, &Options::quick())
        .unwrap_err()
        .to_string();
    assert!(e.contains("broken.txt:1") && e.contains("n=eight"), "{e}");

    let mut dup = inputs();
    dup.kernels.push(("again.txt".into(), KERNELS_M3.into()));
    let e = accuracy_cost::generate(&dup, &Options::quick())
        .unwrap_err()
        .to_string();
    assert!(e.contains("again.txt:1") && e.contains("m3.txt:1"), "{e}");

    let mut elf = inputs();
    elf.elfs
        .push(("thumbv7em-none-eabihf".into(), b"not an elf".to_vec()));
    let e = accuracy_cost::generate(&elf, &Options::quick())
        .unwrap_err()
        .to_string();
    assert!(e.contains("thumbv7em-none-eabihf"), "{e}");
}
