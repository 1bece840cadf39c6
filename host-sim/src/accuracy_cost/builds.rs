//! Two builds of the kernel-cost firmware compared kernel by kernel: how a
//! build flag moves estimated cycles and instructions (the report's "Build
//! flags" section).

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
