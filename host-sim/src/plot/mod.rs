//! The one plot writer: a data-only description of a plot ([`Plot`],
//! [`Series`]) that callers fill in without touching the drawing library,
//! drawn with `plotters` into SVG (a `String`, callers write the file) or
//! PNG (on request).
//!
//! - Axes are labelled with units, linear or logarithmic ([`Plot::x_log`],
//!   [`Plot::y_log`]); points that cannot be drawn (non-finite, or not
//!   positive on a log axis) are skipped, and a line is broken there.
//! - Line series with more points than the plot has pixel columns are
//!   decimated inside the writer ([`decimate`]): per pixel column the
//!   first, lowest, highest and last point, in their order, so that a dense
//!   oscillation shows as its envelope and the file stays small.
//! - The legend sits inside the plot area, in the corner with the fewest
//!   points unless the plot names one ([`Legend`]), on a semi-transparent
//!   background.
//! - Text (titles and series names come from scene files) is made safe:
//!   the control characters XML forbids are dropped, markup characters are
//!   escaped by the SVG backend, and over-long text is shrunk or cut with
//!   an ellipsis. [`well_formed`] checks a document for the tests.
//! - Several plots stack top to bottom in one figure ([`render_panels`]),
//!   each panel an SVG group `<g transform="translate(0 y)">`.
//! - Text is measured (and drawn, in PNG) with DejaVu Sans compiled into
//!   the binary, so the output depends on no system font and the same
//!   input always gives the same bytes.

mod axis;
mod decimate;
mod draw;
mod xml;

use std::path::{Path, PathBuf};

pub use axis::{log_ticks, ticks};
pub use decimate::decimate;
pub use xml::{sanitize, well_formed};

/// Width of a plot, px.
pub const WIDTH: u32 = 800;
/// Height of one panel, px.
pub const PANEL_HEIGHT: u32 = 560;

/// A colour, 8 bits a channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// Black.
    pub const BLACK: Rgb = Rgb(0, 0, 0);
    /// Mid grey.
    pub const GREY: Rgb = Rgb(0x55, 0x55, 0x55);
}

/// The colours series take in turn (colour-blind safe first).
pub const PALETTE: [Rgb; 10] = [
    Rgb(0x00, 0x72, 0xb2),
    Rgb(0xd5, 0x5e, 0x00),
    Rgb(0x00, 0x9e, 0x73),
    Rgb(0xcc, 0x79, 0xa7),
    Rgb(0xe6, 0x9f, 0x00),
    Rgb(0x56, 0xb4, 0xe9),
    Rgb(0x7b, 0x32, 0x94),
    Rgb(0x4d, 0x4d, 0x4d),
    Rgb(0xb2, 0x18, 0x2b),
    Rgb(0x1b, 0x78, 0x37),
];

/// The `i`-th colour of [`PALETTE`], cycling.
pub fn palette(i: usize) -> Rgb {
    PALETTE[i % PALETTE.len()]
}

/// Shape of a marker.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Shape {
    /// A disc.
    #[default]
    Circle,
    /// A square.
    Square,
    /// A triangle pointing up.
    Triangle,
    /// A diamond.
    Diamond,
    /// A triangle pointing down.
    TriangleDown,
    /// A diagonal cross (never filled).
    Cross,
}

impl Shape {
    /// Every shape, to give families of points one each.
    pub const ALL: [Shape; 6] = [
        Shape::Circle,
        Shape::Square,
        Shape::Triangle,
        Shape::Diamond,
        Shape::TriangleDown,
        Shape::Cross,
    ];

    /// The `i`-th shape of [`Shape::ALL`], cycling.
    pub fn nth(i: usize) -> Shape {
        Self::ALL[i % Self::ALL.len()]
    }
}

/// How markers are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Marker {
    /// Shape.
    pub shape: Shape,
    /// Half the size, px.
    pub radius: u32,
    /// Filled (semi-transparent, with an outline) or outline only.
    pub filled: bool,
}

impl Default for Marker {
    fn default() -> Self {
        Self {
            shape: Shape::Circle,
            radius: 3,
            filled: true,
        }
    }
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Style {
    /// A line through the points, in order (decimated when dense).
    #[default]
    Line,
    /// A dashed line through the points (reference lines).
    Dashed,
    /// One marker per point, not joined.
    Markers(Marker),
}

/// One curve or set of points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Series {
    /// Legend text; a series with an empty name has no legend entry (and a
    /// named series without points has only its legend entry).
    pub name: String,
    /// (x, y) points, in order.
    pub points: Vec<(f64, f64)>,
    /// Line, dashed line or markers.
    pub style: Style,
    /// Colour; `None` takes the series' index in [`PALETTE`].
    pub color: Option<Rgb>,
}

impl Series {
    /// A series drawn as a line.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: Style::Line,
            color: None,
        }
    }

    /// A series drawn as a dashed line.
    pub fn dashed(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            style: Style::Dashed,
            ..Self::line(name, points)
        }
    }

    /// A series drawn as markers (filled discs).
    pub fn markers(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            style: Style::Markers(Marker::default()),
            ..Self::line(name, points)
        }
    }

    /// The same series in colour `color`.
    pub fn with_color(mut self, color: Rgb) -> Self {
        self.color = Some(color);
        self
    }

    /// The same series drawn with `marker`.
    pub fn with_marker(mut self, marker: Marker) -> Self {
        self.style = Style::Markers(marker);
        self
    }
}

/// Where the legend goes, inside the plot area.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Legend {
    /// The corner that covers the fewest points (upper right on a tie).
    #[default]
    Auto,
    /// Upper left corner.
    UpperLeft,
    /// Upper right corner.
    UpperRight,
    /// Lower left corner.
    LowerLeft,
    /// Lower right corner.
    LowerRight,
    /// No legend.
    Hidden,
}

/// A plot with labelled axes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Plot {
    /// Title on top.
    pub title: String,
    /// Horizontal axis label, with unit.
    pub x_label: String,
    /// Vertical axis label, with unit.
    pub y_label: String,
    /// Logarithmic horizontal axis (points with x <= 0 are not drawn).
    pub x_log: bool,
    /// Logarithmic vertical axis (points with y <= 0 are not drawn).
    pub y_log: bool,
    /// Where the legend goes.
    pub legend: Legend,
    /// Curves, drawn in order (the last on top).
    pub series: Vec<Series>,
}

impl Plot {
    /// A plot with linear axes and no series yet.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Self::default()
        }
    }

    /// The plot as a standalone SVG document.
    pub fn render(&self) -> String {
        render_panels(std::slice::from_ref(self))
    }

    /// The plot as a PNG image.
    pub fn png(&self) -> Result<Vec<u8>, PlotError> {
        png_panels(std::slice::from_ref(self))
    }

    /// Writes the plot as a PNG image to `path`.
    pub fn write_png(&self, path: &Path) -> Result<(), PlotError> {
        write_panels(std::slice::from_ref(self), path, Format::Png)
    }
}

/// An output format.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Format {
    /// SVG text.
    #[default]
    Svg,
    /// PNG image, [`WIDTH`] px wide.
    Png,
}

impl Format {
    /// File name extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Svg => "svg",
            Format::Png => "png",
        }
    }
}

/// Why a plot could not be drawn or written.
#[derive(Debug)]
pub enum PlotError {
    /// The compiled-in font could not be registered.
    Font(String),
    /// The drawing library failed.
    Draw(String),
    /// The PNG encoder failed.
    Encode(String),
    /// The file could not be written.
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        error: std::io::Error,
    },
}

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlotError::Font(e) => write!(f, "plot font: {e}"),
            PlotError::Draw(e) => write!(f, "drawing a plot: {e}"),
            PlotError::Encode(e) => write!(f, "encoding a PNG: {e}"),
            PlotError::Io { path, error } => write!(f, "{}: {error}", path.display()),
        }
    }
}

impl std::error::Error for PlotError {}

/// Plots stacked top to bottom in one SVG document (panels that share a
/// time axis, for example).
///
/// Never fails: if drawing does (it cannot with the compiled-in font), the
/// document is a blank figure that says why.
pub fn render_panels(plots: &[Plot]) -> String {
    svg_panels(plots).unwrap_or_else(|e| draw::error_svg(&e.to_string()))
}

/// [`render_panels`], with the error instead of the blank figure.
pub fn svg_panels(plots: &[Plot]) -> Result<String, PlotError> {
    draw::svg(plots)
}

/// Plots stacked top to bottom in one PNG image.
pub fn png_panels(plots: &[Plot]) -> Result<Vec<u8>, PlotError> {
    draw::png(plots)
}

/// Writes plots stacked top to bottom to `path` in `format`.
pub fn write_panels(plots: &[Plot], path: &Path, format: Format) -> Result<(), PlotError> {
    let bytes = match format {
        Format::Svg => svg_panels(plots)?.into_bytes(),
        Format::Png => png_panels(plots)?,
    };
    std::fs::write(path, bytes).map_err(|error| PlotError::Io {
        path: path.to_path_buf(),
        error,
    })
}
