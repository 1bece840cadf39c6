//! The bushing of the C API: a backbone and any of the core's effects,
//! sized at run time up to fixed capacities, built from a C spec struct.
//!
//! The banks run the core's slice kernels (`maxwell::step_cells`,
//! `iwan::step_clamp`, `xf::step_xf`), the code the const-size banks run,
//! on their first n cells; the spline is the core's `MonotoneSpline` of
//! capacity [`BUSHING_MAX_POINTS`], whose spare pieces repeat the last
//! one. A C bushing therefore computes, bit for bit, what the Rust bushing
//! of the same cells computes (the effects are summed in the order of the
//! spec: Maxwell, Iwan, x_f, STS, friction).

use bushing::iwan::{self, ClampCell, Held};
use bushing::maxwell::{self, MaxwellCell};
use bushing::stack::{FirstLoading, Sts, TurningPoints};
use bushing::xf::{self, XfCell, XfForm};
use bushing::{
    Backbone, Berg, BoucWen, Bushing, BushingState, Dahl, Drive, Effect, EffectOutput,
    IwanCellSpec, MaxwellForm, MaxwellSpec, MonotoneSpline, Param, ParamError, Plain, Polynomial,
    Real, XfSpec,
};

use crate::status::{BushingError, Field};

/// Capacity of the backbone: spline points or polynomial coefficients.
pub const BUSHING_MAX_POINTS: usize = 16;
/// Capacity of the Maxwell bank.
pub const BUSHING_MAX_MAXWELL: usize = 8;
/// Capacity of the Iwan (clamp Jenkins) bank.
pub const BUSHING_MAX_IWAN: usize = 16;
/// Capacity of the x_f bank.
pub const BUSHING_MAX_XF: usize = 4;
/// Turning points the STS stack keeps.
pub const BUSHING_STS_POINTS: usize = 16;
/// Parameters of a friction cell.
pub const BUSHING_FRICTION_PARAMS: usize = 5;

/// Backbone: monotone cubic spline through `points` points (`x_mm`,
/// `force_n`).
pub const BUSHING_BACKBONE_SPLINE: u32 = 0;
/// Backbone: polynomial `Σ force_n[k] x^k` of `points` coefficients on
/// `range_mm`, extended linearly outside it.
pub const BUSHING_BACKBONE_POLYNOMIAL: u32 = 1;

/// Maxwell forms, as the core's `MaxwellForm` (seed 000 §1.3.2).
pub const BUSHING_MAXWELL_LOAD_EXPLICIT: u32 = 0;
/// Eq 1.15.
pub const BUSHING_MAXWELL_LOAD_EXPONENTIAL: u32 = 1;
/// Eq 1.16.
pub const BUSHING_MAXWELL_RATE_EXPLICIT: u32 = 2;
/// Eq 1.17.
pub const BUSHING_MAXWELL_RATE_MIDPOINT: u32 = 3;
/// The exact integral for a ramp of the backbone force (the firmware's).
pub const BUSHING_MAXWELL_RATE_EXACT_RAMP: u32 = 4;

/// x_f forms: midpoint (eq 2.41).
pub const BUSHING_XF_MIDPOINT: u32 = 0;
/// x_f forms: exact for a ramp.
pub const BUSHING_XF_EXACT_RAMP: u32 = 1;

/// No STS stack.
pub const BUSHING_STS_NONE: u32 = 0;
/// STS stack, Masing first loading.
pub const BUSHING_STS_MASING: u32 = 1;
/// STS stack, the initial point a turning point (eq 1.42).
pub const BUSHING_STS_IGNORED: u32 = 2;

/// No friction cell.
pub const BUSHING_FRICTION_NONE: u32 = 0;
/// Dahl cell (eq 1.43): `friction[] = {k_d, f_f, alpha}`.
pub const BUSHING_FRICTION_DAHL: u32 = 1;
/// Bouc-Wen cell (eq 1.44): `friction[] = {alpha, a, beta, gamma, n}`.
pub const BUSHING_FRICTION_BOUC_WEN: u32 = 2;
/// Berg cell (eq 1.45): `friction[] = {f_max, x2}`.
pub const BUSHING_FRICTION_BERG: u32 = 3;

/// A bushing as C describes it: the backbone and the effects, each effect
/// present when its count (or kind) is not zero. Units: mm, N, s, Hz.
/// Entries past a count are ignored.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct BushingSpec {
    /// Time step, s.
    pub dt_s: f64,
    /// `BUSHING_BACKBONE_SPLINE` or `BUSHING_BACKBONE_POLYNOMIAL`.
    pub backbone: u32,
    /// Spline points, or polynomial coefficients (2 to 16; a polynomial
    /// at most 8).
    pub points: u32,
    /// Spline abscissae, mm, increasing.
    pub x_mm: [f64; BUSHING_MAX_POINTS],
    /// Spline forces, N, increasing; or the polynomial's coefficients c_k,
    /// N/mm^k.
    pub force_n: [f64; BUSHING_MAX_POINTS],
    /// Polynomial range `[lo, hi]`, mm.
    pub range_mm: [f64; 2],
    /// `BUSHING_MAXWELL_*`.
    pub maxwell_form: u32,
    /// Maxwell cells (0 for none).
    pub maxwell_cells: u32,
    /// Corner frequency of each cell, Hz.
    pub maxwell_hz: [f64; BUSHING_MAX_MAXWELL],
    /// Load fraction g of each cell.
    pub maxwell_g: [f64; BUSHING_MAX_MAXWELL],
    /// Jenkins cells of the Iwan bank, clamp form (0 for none).
    pub iwan_cells: u32,
    /// Load fraction g of each Jenkins cell.
    pub iwan_g: [f64; BUSHING_MAX_IWAN],
    /// Slip force of each Jenkins cell, N.
    pub iwan_slip_n: [f64; BUSHING_MAX_IWAN],
    /// `BUSHING_XF_*`.
    pub xf_form: u32,
    /// x_f cells (0 for none).
    pub xf_cells: u32,
    /// Viscous relaxation frequency of each x_f cell, Hz (0: rate
    /// independent).
    pub xf_hz: [f64; BUSHING_MAX_XF],
    /// Load fraction g of each x_f cell.
    pub xf_g: [f64; BUSHING_MAX_XF],
    /// Hysteretic relaxation distance x_f of each cell, mm.
    pub xf_distance_mm: [f64; BUSHING_MAX_XF],
    /// `BUSHING_STS_*`.
    pub sts: u32,
    /// STS constant C, N²/mm.
    pub sts_c: f64,
    /// STS stiffness at a turning point K_1, N/mm.
    pub sts_k1: f64,
    /// `BUSHING_FRICTION_*`.
    pub friction: u32,
    /// The friction cell's parameters (see its kind).
    pub friction_params: [f64; BUSHING_FRICTION_PARAMS],
}

/// The backbone of a C bushing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum AnyBackbone<T> {
    Spline(MonotoneSpline<T, BUSHING_MAX_POINTS>),
    Polynomial(Polynomial<T, 8>),
}

impl<T: Real> Backbone<T> for AnyBackbone<T> {
    #[inline]
    fn eval(&self, x: T) -> (T, T) {
        match self {
            Self::Spline(s) => s.eval(x),
            Self::Polynomial(p) => p.eval(x),
        }
    }
}

/// First `n` entries of a capacity array, as a slice.
fn first<X>(items: &[X], n: usize) -> &[X] {
    items.get(..n).unwrap_or(items)
}

/// First `n` entries, mutably.
fn first_mut<X>(items: &mut [X], n: usize) -> &mut [X] {
    let len = items.len();
    items.get_mut(..n.min(len)).unwrap_or_default()
}

/// A Maxwell bank of up to [`BUSHING_MAX_MAXWELL`] cells, plain states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Maxwell<T> {
    form: MaxwellForm,
    cells: [MaxwellCell<T>; BUSHING_MAX_MAXWELL],
    n: usize,
    tangent_gain: T,
    fraction: f64,
    dt: f64,
}

impl<T: Real> Effect<T> for Maxwell<T> {
    type State = [Plain<T>; BUSHING_MAX_MAXWELL];
    type Report = EffectOutput<T>;
    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        Some(self.dt)
    }
    fn rest(&self, _: T) -> Self::State {
        [Plain::default(); BUSHING_MAX_MAXWELL]
    }
    #[inline]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        let cells = first(&self.cells, self.n);
        let states = first_mut(state, self.n);
        maxwell::step_cells(self.form, cells, states, self.tangent_gain, drive)
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// An Iwan bank of up to [`BUSHING_MAX_IWAN`] clamp Jenkins cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Iwan<T> {
    cells: [ClampCell<T>; BUSHING_MAX_IWAN],
    n: usize,
    fraction: f64,
}

impl<T: Real> Effect<T> for Iwan<T> {
    type State = ([T; BUSHING_MAX_IWAN], Held<T>);
    type Report = EffectOutput<T>;
    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        None
    }
    fn rest(&self, _: T) -> Self::State {
        ([T::ZERO; BUSHING_MAX_IWAN], Held::default())
    }
    #[inline]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        let (forces, held) = state;
        iwan::step_clamp(
            first(&self.cells, self.n),
            first_mut(forces, self.n),
            held,
            drive,
        )
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// An x_f bank of up to [`BUSHING_MAX_XF`] cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Xf<T> {
    form: XfForm,
    cells: [XfCell<T>; BUSHING_MAX_XF],
    n: usize,
    fraction: f64,
    dt: f64,
}

impl<T: Real> Effect<T> for Xf<T> {
    type State = [T; BUSHING_MAX_XF];
    type Report = EffectOutput<T>;
    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        Some(self.dt)
    }
    fn rest(&self, _: T) -> Self::State {
        [T::ZERO; BUSHING_MAX_XF]
    }
    #[inline]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        xf::step_xf(
            self.form,
            first(&self.cells, self.n),
            first_mut(state, self.n),
            drive,
        )
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// One friction cell of the core.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Friction<T> {
    Dahl(Dahl<T>),
    BoucWen(BoucWen<T>),
    Berg(Berg<T>),
}

/// Runs `$body` on the cell inside a [`Friction`], whatever its kind.
macro_rules! each_cell {
    ($f:expr, $c:ident => $body:expr) => {
        match $f {
            Friction::Dahl($c) => $body,
            Friction::BoucWen($c) => $body,
            Friction::Berg($c) => $body,
        }
    };
}

impl<T: Real> Effect<T> for Friction<T> {
    type State = <Dahl<T> as Effect<T>>::State;
    type Report = EffectOutput<T>;
    fn fraction(&self) -> f64 {
        each_cell!(self, c => c.fraction())
    }
    fn dt(&self) -> Option<f64> {
        each_cell!(self, c => c.dt())
    }
    fn rest(&self, x0: T) -> Self::State {
        each_cell!(self, c => c.rest(x0))
    }
    #[inline]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        each_cell!(self, c => c.step(state, drive))
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// The STS turning-point stack of a C bushing.
type StsStack<T> = TurningPoints<Sts<T>, BUSHING_STS_POINTS>;

/// The effects of a C bushing: those the spec names, stepped in the
/// order Maxwell, Iwan, x_f, STS, friction. Their outputs are summed from
/// the first present one, as the core's tuple of the same effects sums
/// them; an absent effect adds nothing and costs one branch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Effects<T: Real> {
    maxwell: Option<Maxwell<T>>,
    iwan: Option<Iwan<T>>,
    xf: Option<Xf<T>>,
    sts: Option<StsStack<T>>,
    friction: Option<Friction<T>>,
}

/// A copy of `x` when `on` (an effect's state kept aside for a refused
/// step; none for an absent effect).
#[inline(always)]
fn kept<X: Copy>(on: bool, x: &X) -> Option<X> {
    if on { Some(*x) } else { None }
}

/// Puts a state kept by [`kept`] back.
#[inline(always)]
fn put_back<X>(slot: &mut X, saved: Option<X>) {
    if let Some(x) = saved {
        *slot = x;
    }
}

/// The states of [`Effects`] (an absent effect's is never read).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct EffectsState<T: Real> {
    maxwell: <Maxwell<T> as Effect<T>>::State,
    iwan: <Iwan<T> as Effect<T>>::State,
    xf: <Xf<T> as Effect<T>>::State,
    sts: Option<<StsStack<T> as Effect<T>>::State>,
    friction: Option<<Friction<T> as Effect<T>>::State>,
}

/// A step of [`Effects`]: the summed output and the sum of each effect's
/// `|force| + |tangent|` (the bushing's guard on every effect).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Report<T> {
    total: Option<EffectOutput<T>>,
    magnitude: T,
}

impl<T: Real> Report<T> {
    /// Adds one effect's output.
    #[inline(always)]
    fn add(&mut self, o: EffectOutput<T>) {
        let m = o.force.abs() + o.tangent.abs();
        (self.total, self.magnitude) = match self.total {
            None => (Some(o), m),
            Some(t) => (
                Some(EffectOutput {
                    force: t.force + o.force,
                    tangent: t.tangent + o.tangent,
                    dissipated: t.dissipated + o.dissipated,
                }),
                self.magnitude + m,
            ),
        };
    }
}

impl<T: Real> Effect<T> for Effects<T> {
    type State = EffectsState<T>;
    type Report = Report<T>;

    fn fraction(&self) -> f64 {
        let parts = [
            self.maxwell.fraction(),
            self.iwan.fraction(),
            self.xf.fraction(),
            self.sts.fraction(),
            self.friction.fraction(),
        ];
        parts.iter().sum()
    }
    fn dt(&self) -> Option<f64> {
        self.check_dt(None).ok().flatten()
    }
    fn check_dt(&self, dt: Option<f64>) -> Result<Option<f64>, ParamError> {
        let dt = self.maxwell.check_dt(dt)?;
        let dt = self.iwan.check_dt(dt)?;
        let dt = self.xf.check_dt(dt)?;
        let dt = self.sts.check_dt(dt)?;
        self.friction.check_dt(dt)
    }
    fn rest(&self, x0: T) -> Self::State {
        EffectsState {
            maxwell: [Plain::default(); BUSHING_MAX_MAXWELL],
            iwan: ([T::ZERO; BUSHING_MAX_IWAN], Held::default()),
            xf: [T::ZERO; BUSHING_MAX_XF],
            sts: self.sts.rest(x0),
            friction: self.friction.rest(x0),
        }
    }
    #[inline(always)]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> Report<T> {
        let mut r = Report {
            total: None,
            magnitude: T::ZERO,
        };
        if let Some(e) = &self.maxwell {
            r.add(e.step(&mut state.maxwell, drive));
        }
        if let Some(e) = &self.iwan {
            r.add(e.step(&mut state.iwan, drive));
        }
        if let Some(e) = &self.xf {
            r.add(e.step(&mut state.xf, drive));
        }
        if let (Some(e), Some(s)) = (&self.sts, &mut state.sts) {
            r.add(e.step(s, drive));
        }
        if let (Some(e), Some(s)) = (&self.friction, &mut state.friction) {
            r.add(e.step(s, drive));
        }
        r
    }
    fn total(report: &Report<T>) -> EffectOutput<T> {
        report.total.unwrap_or(EffectOutput::zero())
    }
    fn magnitude(report: &Report<T>) -> T {
        report.magnitude
    }
    /// Steps every present effect after keeping its state aside, and puts
    /// them back if `accept` refuses the report (a refused step is rare:
    /// the copies are a few words for the banks).
    #[inline(always)]
    fn step_if(
        &self,
        state: &mut Self::State,
        drive: &Drive<T>,
        accept: impl FnOnce(&Report<T>) -> bool,
    ) -> Option<Report<T>> {
        let maxwell = kept(self.maxwell.is_some(), &state.maxwell);
        let iwan = kept(self.iwan.is_some(), &state.iwan);
        let xf = kept(self.xf.is_some(), &state.xf);
        let sts = kept(self.sts.is_some(), &state.sts);
        let friction = kept(self.friction.is_some(), &state.friction);
        let report = self.step(state, drive);
        if accept(&report) {
            return Some(report);
        }
        put_back(&mut state.maxwell, maxwell);
        put_back(&mut state.iwan, iwan);
        put_back(&mut state.xf, xf);
        put_back(&mut state.sts, sts);
        put_back(&mut state.friction, friction);
        None
    }
}

/// A C bushing.
pub(crate) type Model<T> = Bushing<T, AnyBackbone<T>, Effects<T>>;
/// Its state.
pub(crate) type State<T> = BushingState<T, <Effects<T> as Effect<T>>::State>;

/// A count field within its capacity.
fn within(name: &'static str, n: u32, capacity: usize) -> Result<usize, ParamError> {
    let n = n as usize;
    if n > capacity {
        return Err(ParamError::TooMany {
            param: Param::scalar(name),
            capacity,
            got: n,
        });
    }
    Ok(n)
}

/// The cells `0..n` built by `cell`, into a capacity array (the rest
/// default).
fn cells<C: Copy + Default, const N: usize>(
    n: usize,
    mut cell: impl FnMut(usize) -> Result<C, ParamError>,
) -> Result<[C; N], ParamError> {
    let mut out = [C::default(); N];
    for (i, c) in out.iter_mut().enumerate().take(n) {
        *c = cell(i)?;
    }
    Ok(out)
}

/// Entry `i` of a spec array (every index used is below its capacity).
fn at(values: &[f64], i: usize) -> f64 {
    values.get(i).copied().unwrap_or(f64::NAN)
}

/// The C fields of the backbone's parameters.
const BACKBONE_FIELDS: [Field; 7] = [
    ("x", "x_mm", None),
    ("force", "force_n", None),
    ("coefficients", "force_n", None),
    ("range", "range_mm", None),
    ("range.lo", "range_mm", Some(0)),
    ("range.hi", "range_mm", Some(1)),
    ("stiffness", "force_n", Some(1)),
];
/// The C fields of the Maxwell cells' parameters.
const MAXWELL_FIELDS: [Field; 3] = [
    ("g", "maxwell_g", None),
    ("omega", "maxwell_hz", None),
    ("dt", "dt_s", None),
];
/// The C fields of the Jenkins cells' parameters.
const IWAN_FIELDS: [Field; 2] = [("g", "iwan_g", None), ("slip_force", "iwan_slip_n", None)];
/// The C fields of the x_f cells' parameters.
const XF_FIELDS: [Field; 5] = [
    ("g", "xf_g", None),
    ("omega", "xf_hz", None),
    ("omega dt", "xf_hz", None),
    ("x_f", "xf_distance_mm", None),
    ("dt", "dt_s", None),
];
/// The C fields of the STS law's parameters.
const STS_FIELDS: [Field; 2] = [("c", "sts_c", None), ("k1", "sts_k1", None)];
/// The Dahl cell's parameters, by their place in `friction_params`.
const DAHL_FIELDS: [Field; 3] = [
    ("k_d", "friction_params", Some(0)),
    ("f_f", "friction_params", Some(1)),
    ("alpha", "friction_params", Some(2)),
];
/// The Bouc-Wen cell's parameters, by their place in `friction_params`.
const BOUC_WEN_FIELDS: [Field; 6] = [
    ("alpha", "friction_params", Some(0)),
    ("a", "friction_params", Some(1)),
    ("beta", "friction_params", Some(2)),
    ("beta - |gamma|", "friction_params", Some(3)),
    ("n", "friction_params", Some(4)),
    ("(a / (beta + gamma))^(1/n)", "friction_params", Some(1)),
];
/// The Berg cell's parameters, by their place in `friction_params`.
const BERG_FIELDS: [Field; 2] = [
    ("f_max", "friction_params", Some(0)),
    ("x2", "friction_params", Some(1)),
];

/// A refusal of the core, in the C spec's words.
fn refused(fields: &[Field]) -> impl Fn(ParamError) -> BushingError + '_ {
    move |e| BushingError::from(e).in_fields(fields)
}

fn backbone<T: Real>(spec: &BushingSpec) -> Result<AnyBackbone<T>, BushingError> {
    let n = within("points", spec.points, BUSHING_MAX_POINTS)?;
    match spec.backbone {
        BUSHING_BACKBONE_SPLINE => {
            MonotoneSpline::new(first(&spec.x_mm, n), first(&spec.force_n, n))
                .map(AnyBackbone::Spline)
                .map_err(refused(&BACKBONE_FIELDS))
        }
        BUSHING_BACKBONE_POLYNOMIAL => Polynomial::new(
            first(&spec.force_n, n),
            (spec.range_mm[0], spec.range_mm[1]),
        )
        .map(AnyBackbone::Polynomial)
        .map_err(refused(&BACKBONE_FIELDS)),
        other => Err(BushingError::unknown_kind("backbone", other)),
    }
}

fn maxwell<T: Real>(spec: &BushingSpec) -> Result<Option<Maxwell<T>>, BushingError> {
    let n = within("maxwell_cells", spec.maxwell_cells, BUSHING_MAX_MAXWELL)?;
    if n == 0 {
        return Ok(None);
    }
    let form = MaxwellForm::ALL
        .get(spec.maxwell_form as usize)
        .copied()
        .ok_or(BushingError::unknown_kind(
            "maxwell_form",
            spec.maxwell_form,
        ))?;
    let specs = |i| MaxwellSpec::hz(at(&spec.maxwell_hz, i), at(&spec.maxwell_g, i));
    let cells = cells(n, |i| MaxwellCell::new(form, specs(i), spec.dt_s, i))
        .map_err(refused(&MAXWELL_FIELDS))?;
    Ok(Some(Maxwell {
        form,
        tangent_gain: maxwell::tangent_gain(first(&cells, n)),
        cells,
        n,
        fraction: (0..n).map(|i| at(&spec.maxwell_g, i)).sum(),
        dt: spec.dt_s,
    }))
}

fn iwan<T: Real>(spec: &BushingSpec) -> Result<Option<Iwan<T>>, BushingError> {
    let n = within("iwan_cells", spec.iwan_cells, BUSHING_MAX_IWAN)?;
    if n == 0 {
        return Ok(None);
    }
    let specs = |i| IwanCellSpec::new(at(&spec.iwan_g, i), at(&spec.iwan_slip_n, i));
    Ok(Some(Iwan {
        cells: cells(n, |i| ClampCell::new(specs(i), i)).map_err(refused(&IWAN_FIELDS))?,
        n,
        fraction: (0..n).map(|i| at(&spec.iwan_g, i)).sum(),
    }))
}

fn xf<T: Real>(spec: &BushingSpec) -> Result<Option<Xf<T>>, BushingError> {
    let n = within("xf_cells", spec.xf_cells, BUSHING_MAX_XF)?;
    if n == 0 {
        return Ok(None);
    }
    let form = XfForm::ALL
        .get(spec.xf_form as usize)
        .copied()
        .ok_or(BushingError::unknown_kind("xf_form", spec.xf_form))?;
    let specs = |i| {
        XfSpec::hz(
            at(&spec.xf_hz, i),
            at(&spec.xf_g, i),
            at(&spec.xf_distance_mm, i),
        )
    };
    Ok(Some(Xf {
        form,
        cells: cells(n, |i| XfCell::new(specs(i), spec.dt_s, i)).map_err(refused(&XF_FIELDS))?,
        n,
        fraction: (0..n).map(|i| at(&spec.xf_g, i)).sum(),
        dt: spec.dt_s,
    }))
}

fn sts<T: Real>(
    spec: &BushingSpec,
) -> Result<Option<TurningPoints<Sts<T>, BUSHING_STS_POINTS>>, BushingError> {
    let first_loading = match spec.sts {
        BUSHING_STS_NONE => return Ok(None),
        BUSHING_STS_MASING => FirstLoading::Masing,
        BUSHING_STS_IGNORED => FirstLoading::Ignored,
        other => return Err(BushingError::unknown_kind("sts", other)),
    };
    let law = Sts::new(spec.sts_c, spec.sts_k1).map_err(refused(&STS_FIELDS))?;
    Ok(Some(TurningPoints::new(law, first_loading)))
}

fn friction<T: Real>(spec: &BushingSpec) -> Result<Option<Friction<T>>, BushingError> {
    let [p0, p1, p2, p3, p4] = spec.friction_params;
    Ok(Some(match spec.friction {
        BUSHING_FRICTION_NONE => return Ok(None),
        BUSHING_FRICTION_DAHL => {
            Friction::Dahl(Dahl::new(p0, p1, p2).map_err(refused(&DAHL_FIELDS))?)
        }
        BUSHING_FRICTION_BOUC_WEN => {
            Friction::BoucWen(BoucWen::new(p0, p1, p2, p3, p4).map_err(refused(&BOUC_WEN_FIELDS))?)
        }
        BUSHING_FRICTION_BERG => Friction::Berg(Berg::new(p0, p1).map_err(refused(&BERG_FIELDS))?),
        other => return Err(BushingError::unknown_kind("friction", other)),
    }))
}

/// The bushing of `spec`, every parameter checked by the core's
/// constructors.
pub(crate) fn build<T: Real>(spec: &BushingSpec) -> Result<Model<T>, BushingError> {
    let effects = Effects {
        maxwell: maxwell(spec)?,
        iwan: iwan(spec)?,
        xf: xf(spec)?,
        sts: sts(spec)?,
        friction: friction(spec)?,
    };
    Ok(Bushing::new(backbone(spec)?, effects)?)
}
