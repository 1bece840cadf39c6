//! Two builds of the kernel-cost firmware compared kernel by kernel: how a
//! build flag moves estimated cycles and instructions (the report's "Build
//! flags" section), and how far the same kernels, with the same flags, cost
//! the same in a binary of other content (the "Harness" section).

use std::collections::BTreeMap;

use super::Key;
use super::firmware::KernelLine;

use super::HEADLINE;

/// One kernel in both builds: (instructions, estimated cycles).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair {
    /// In the report's build.
    pub ours: (f64, f64),
    /// In the other build.
    pub other: (f64, f64),
}

/// The comparison of the report's build with another.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// What the other build is (its flags).
    pub other: String,
    /// Kernels with cycles in both builds.
    pub kernels: usize,
    /// Geometric mean over them of cycles (report's build / other).
    pub cycles_ratio: f64,
    /// The same for instructions.
    pub instructions_ratio: f64,
    /// Kernels with fewer estimated cycles in the report's build.
    pub fewer_cycles: usize,
    /// Kernels with more.
    pub more_cycles: usize,
    /// The [`HEADLINE`] kernels found in both.
    pub named: Vec<(Key, Pair)>,
}

/// Compares the M4F f32 kernels of the report's build (`ours`) with those
/// of `other` (each a kernel's worst input, lines already merged), by
/// estimated cycles and instructions; `None` when no kernel has cycles in
/// both.
pub fn compare<'a>(
    name: &str,
    ours: impl Iterator<Item = &'a KernelLine>,
    other: impl Iterator<Item = &'a KernelLine>,
) -> Option<Comparison> {
    let index = |lines: &mut dyn Iterator<Item = &'a KernelLine>| -> BTreeMap<Key, (f64, f64)> {
        lines
            .filter(|l| l.target == "m4f" && l.number == "f32")
            .filter_map(|l| {
                let key = Key::new(&l.family, &l.name, l.n, &l.number);
                Some((key, (l.instructions(), l.cycles?)))
            })
            .collect()
    };
    let (mut ours, mut other) = (ours, other);
    let a = index(&mut ours);
    let b = index(&mut other);
    let pairs: Vec<(&Key, Pair)> = a
        .iter()
        .filter_map(|(k, &o)| {
            let t = *b.get(k)?;
            (o.0 > 0.0 && o.1 > 0.0 && t.0 > 0.0 && t.1 > 0.0)
                .then_some((k, Pair { ours: o, other: t }))
        })
        .collect();
    if pairs.is_empty() {
        return None;
    }
    let geomean = |f: &dyn Fn(&Pair) -> f64| {
        let logs: f64 = pairs.iter().map(|(_, p)| f(p).ln()).sum();
        (logs / pairs.len() as f64).exp()
    };
    let named = HEADLINE
        .iter()
        .filter_map(|&(family, name, n)| {
            let key = Key::new(family, name, n, "f32");
            let pair = pairs.iter().find(|(k, _)| **k == key)?.1;
            Some((key, pair))
        })
        .collect();
    Some(Comparison {
        other: name.into(),
        kernels: pairs.len(),
        cycles_ratio: geomean(&|p| p.ours.1 / p.other.1),
        instructions_ratio: geomean(&|p| p.ours.0 / p.other.0),
        fewer_cycles: pairs.iter().filter(|(_, p)| p.ours.1 < p.other.1).count(),
        more_cycles: pairs.iter().filter(|(_, p)| p.ours.1 > p.other.1).count(),
        named,
    })
}

/// One kernel on one input in two binaries: (instructions, estimated
/// cycles) in each.
#[derive(Debug, Clone, PartialEq)]
pub struct SpreadRow {
    /// The kernel.
    pub key: Key,
    /// The input's name.
    pub input: String,
    /// In the report's binary.
    pub ours: (f64, Option<f64>),
    /// In the other binary.
    pub other: (f64, Option<f64>),
}

impl SpreadRow {
    /// |instructions here - there|.
    pub fn instructions(&self) -> f64 {
        (self.ours.0 - self.other.0).abs()
    }

    /// |cycles here - there| (0 when either has none).
    pub fn cycles(&self) -> f64 {
        match (self.ours.1, self.other.1) {
            (Some(a), Some(b)) => (a - b).abs(),
            _ => 0.0,
        }
    }
}

/// The same kernels, built with the same flags, measured in two binaries
/// of different content: how much a kernel's count depends on what else
/// its binary holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Spread {
    /// What the other binary is.
    pub other: String,
    /// Every M4F kernel and input measured in both.
    pub rows: Vec<SpreadRow>,
}

impl Spread {
    /// The largest difference in instructions per call.
    pub fn max_instructions(&self) -> f64 {
        self.rows
            .iter()
            .map(SpreadRow::instructions)
            .fold(0.0, f64::max)
    }

    /// The largest difference in estimated cycles per call.
    pub fn max_cycles(&self) -> f64 {
        self.rows.iter().map(SpreadRow::cycles).fold(0.0, f64::max)
    }
}

/// Pairs every M4F kernel and input of `other` with the same kernel and
/// input of `ours` (lines merged, each with its costs by input); `None`
/// when none pairs.
pub fn spread<'a>(
    name: &str,
    ours: impl Iterator<Item = &'a KernelLine>,
    other: impl Iterator<Item = &'a KernelLine>,
) -> Option<Spread> {
    let key = |l: &KernelLine| Key::new(&l.family, &l.name, l.n, &l.number);
    let ours: BTreeMap<Key, &KernelLine> = ours
        .filter(|l| l.target == "m4f")
        .map(|l| (key(l), l))
        .collect();
    let mut rows = Vec::new();
    for theirs in other.filter(|l| l.target == "m4f") {
        let k = key(theirs);
        let Some(mine) = ours.get(&k) else { continue };
        for c in &theirs.by_input {
            if let Some(m) = mine.by_input.iter().find(|m| m.input == c.input) {
                rows.push(SpreadRow {
                    key: k.clone(),
                    input: c.input.clone(),
                    ours: (m.instructions, m.cycles),
                    other: (c.instructions, c.cycles),
                });
            }
        }
    }
    (!rows.is_empty()).then(|| Spread {
        other: name.into(),
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accuracy_cost::firmware::{InputCost, parse_kernels};

    /// A merged M4F f32 line of `name` with its costs by input.
    fn line(name: &str, costs: &[(&str, f64, f64)]) -> KernelLine {
        let text = format!("kernel target=m4f type=f32 family=f name={name} n=1 per_call=1");
        let Ok(mut lines) = parse_kernels("t", &text) else {
            panic!("the line parses")
        };
        let mut l = lines.remove(0);
        l.by_input = costs
            .iter()
            .map(|&(input, instructions, cycles)| InputCost {
                input: input.into(),
                instructions,
                cycles: Some(cycles),
            })
            .collect();
        if let Some(worst) = l.by_input.first() {
            l.net = Some(worst.instructions);
            l.cycles = worst.cycles;
        }
        l
    }

    #[test]
    fn spread_pairs_each_input_and_keeps_the_largest_difference() {
        let ours = [
            line("a", &[("sine", 100.0, 150.0), ("noise", 120.0, 170.0)]),
            line("only-here", &[("sine", 5.0, 5.0)]),
        ];
        let alone = [
            line("a", &[("sine", 100.0, 150.0), ("noise", 123.0, 171.5)]),
            line("only-there", &[("sine", 5.0, 5.0)]),
        ];
        let Some(s) = spread("alone", ours.iter(), alone.iter()) else {
            panic!("kernel a is in both")
        };
        assert_eq!(s.rows.len(), 2);
        assert_eq!(s.max_instructions(), 3.0);
        assert_eq!(s.max_cycles(), 1.5);
        assert_eq!(s.rows[1].input, "noise");
        assert!(spread("alone", ours[1..].iter(), alone[1..].iter()).is_none());
    }

    #[test]
    fn compare_takes_geometric_means_over_the_kernels_in_both() {
        let ours = [
            line("a", &[("sine", 110.0, 90.0)]),
            line("b", &[("sine", 40.0, 50.0)]),
        ];
        let other = [
            line("a", &[("sine", 100.0, 100.0)]),
            line("b", &[("sine", 40.0, 40.0)]),
        ];
        let Some(c) = compare("generic", ours.iter(), other.iter()) else {
            panic!("two kernels in both")
        };
        assert_eq!(c.kernels, 2);
        assert!((c.cycles_ratio - (0.9f64 * 1.25).sqrt()).abs() < 1e-12);
        assert!((c.instructions_ratio - 1.1f64.sqrt()).abs() < 1e-12);
        assert_eq!((c.fewer_cycles, c.more_cycles), (1, 1));
    }
}
