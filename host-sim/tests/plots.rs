//! The plot writer through its public API: dense lines decimated to their
//! envelope, hostile text, empty and degenerate data, log axes, legends
//! inside the plot area, panels, PNG, determinism, and the modulus against
//! frequency. Documents are parsed with roxmltree (an XML parser) as well
//! as checked by the crate's own `well_formed`.

use bushing_sim::plot::{
    self, Format, Legend, Marker, Plot, PlotError, Series, Shape, palette, well_formed,
};
use bushing_sim::probe::{self, ModulusPoint};

/// Parses `svg` as XML, checks it with `well_formed` too, and that no
/// number in it is NaN or infinite.
fn parse(svg: &str) -> roxmltree::Document<'_> {
    well_formed(svg).unwrap_or_else(|e| panic!("{e}"));
    assert!(!svg.contains("NaN") && !svg.contains("inf"), "NaN or inf");
    roxmltree::Document::parse(svg).unwrap_or_else(|e| panic!("{e}"))
}

fn elements<'a>(
    doc: &'a roxmltree::Document<'a>,
    tag: &'a str,
) -> impl Iterator<Item = roxmltree::Node<'a, 'a>> + 'a {
    doc.descendants().filter(move |n| n.has_tag_name(tag))
}

fn attr(n: &roxmltree::Node<'_, '_>, name: &str) -> f64 {
    n.attribute(name)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no numeric {name} in {n:?}"))
}

/// The points of a `<polyline>`.
fn points(n: &roxmltree::Node<'_, '_>) -> Vec<(i64, i64)> {
    n.attribute("points")
        .unwrap_or("")
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect()
}

fn hex(c: plot::Rgb) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

/// The pixel row of the vertical axis' tick labelled `label`.
fn tick_row(doc: &roxmltree::Document<'_>, label: &str) -> f64 {
    let tick = elements(doc, "text")
        .find(|t| t.attribute("text-anchor") == Some("end") && t.text() == Some(label))
        .unwrap_or_else(|| panic!("no tick {label}"));
    attr(&tick, "y")
}

#[test]
fn a_million_point_sine_is_drawn_as_its_envelope() {
    let n = 1_000_000;
    let sine: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let t = i as f64 * 1e-4;
            (t, (std::f64::consts::TAU * t * 10.0).sin())
        })
        .collect();
    let (lo, hi) = sine
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    assert_eq!((lo, hi), (-1.0, 1.0), "the test wants exact extremes");
    let mut p = Plot::new("1e6 points", "time t [s]", "force F [N]");
    p.series.push(Series::line("sine", sine.clone()));
    let svg = p.render();
    assert!(svg.len() < 200_000, "{} bytes", svg.len());
    let doc = parse(&svg);
    let color = hex(palette(0));
    let line = elements(&doc, "polyline")
        .filter(|l| l.attribute("stroke") == Some(color.as_str()))
        .max_by_key(|l| points(l).len())
        .expect("the sine's polyline");
    let pts = points(&line);
    assert!(pts.len() > 500 && pts.len() < 4 * 800, "{}", pts.len());
    let top = pts.iter().map(|p| p.1).min().unwrap() as f64;
    let bottom = pts.iter().map(|p| p.1).max().unwrap() as f64;
    // y grows downwards: the peaks touch the rows of the ticks 1 and -1.
    assert_eq!(top, tick_row(&doc, "1"));
    assert_eq!(bottom, tick_row(&doc, "-1"));
    // In data units the decimated line keeps the extremes exactly.
    let d = plot::decimate(&sine, (0.0, 100.0), 700);
    assert!(d.len() <= 4 * 700);
    let (dlo, dhi) = d
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    assert_eq!((dlo, dhi), (lo, hi));
}

#[test]
fn hostile_text_makes_well_formed_xml() {
    let hostile = "a <b> & \"c\" 'd' ]]> \u{1}\u{7}\u{1b}e\tf\r\ng \u{FFFF}";
    let mut p = Plot::new(hostile, format!("{hostile} [mm]"), "y [N]");
    p.series
        .push(Series::line(hostile, vec![(0.0, 0.0), (1.0, 1.0)]));
    p.series.push(Series::markers(
        "x".repeat(10_000),
        vec![(0.5, 0.5), (f64::NAN, 1.0)],
    ));
    let svg = p.render();
    let doc = parse(&svg);
    let texts: Vec<&str> = elements(&doc, "text").filter_map(|t| t.text()).collect();
    let clean = "a <b> & \"c\" 'd' ]]> e f  g ";
    assert!(texts.contains(&clean), "{texts:?}");
    assert!(texts.contains(&format!("{clean} [mm]").as_str()));
    // The long name is cut with an ellipsis, and stays inside the canvas.
    let long = elements(&doc, "text")
        .find(|t| t.text().is_some_and(|s| s.starts_with("xxx")))
        .unwrap();
    assert!(long.text().unwrap().ends_with('…') && long.text().unwrap().len() < 400);
    // A very long title too.
    let mut p = Plot::new("t".repeat(100_000), "x [mm]", "y [N]");
    p.series
        .push(Series::line("a", vec![(0.0, 0.0), (1.0, 1.0)]));
    let svg = p.render();
    let doc = parse(&svg);
    assert!(elements(&doc, "text").any(|t| t.text().is_some_and(|s| s.ends_with("t…"))));
}

#[test]
fn empty_constant_and_broken_data_still_plot() {
    let cases = [
        vec![],
        vec![Series::line("empty", vec![])],
        vec![Series::line("flat", vec![(0.0, 5.0), (2.0, 5.0)])],
        vec![Series::markers("one point", vec![(3.0, 3.0)])],
        vec![Series::line(
            "broken",
            vec![
                (f64::NAN, 1.0),
                (0.0, f64::INFINITY),
                (1.0, 1.0),
                (2.0, f64::NAN),
                (3.0, 2.0),
                (4.0, 3.0),
            ],
        )],
        vec![Series::line(
            "nothing drawable",
            vec![(f64::NAN, f64::NAN); 3],
        )],
        vec![Series::line("huge", vec![(0.0, -1e308), (1.0, 1e308)])],
        vec![Series::line(
            "subnormal",
            vec![(0.0, -3e-322), (1.0, 3e-322)],
        )],
    ];
    for series in cases {
        for (x_log, y_log) in [(false, false), (true, false), (true, true)] {
            let p = Plot {
                title: "degenerate".into(),
                x_label: "x [mm]".into(),
                y_label: "y [N]".into(),
                x_log,
                y_log,
                series: series.clone(),
                ..Plot::default()
            };
            let svg = p.render();
            parse(&svg);
            assert!(svg.contains("x [mm]") && svg.contains("y [N]"));
            assert!(p.png().is_ok());
        }
    }
    // A constant gets a readable axis around its value.
    let mut p = Plot::new("flat", "x [mm]", "y [N]");
    p.series
        .push(Series::line("flat", vec![(0.0, 5.0), (2.0, 5.0)]));
    let svg = p.render();
    let doc = parse(&svg);
    tick_row(&doc, "5");
    tick_row(&doc, "5.2");
    // The break: the line is drawn as two pieces around the NaN.
    let mut p = Plot::new("broken", "x [mm]", "y [N]");
    p.series.push(Series::line(
        "b",
        vec![
            (0.0, 0.0),
            (1.0, 1.0),
            (2.0, f64::NAN),
            (3.0, 0.0),
            (4.0, 1.0),
        ],
    ));
    let svg = p.render();
    let doc = parse(&svg);
    let color = hex(palette(0));
    let pieces = elements(&doc, "polyline")
        .filter(|l| l.attribute("stroke") == Some(color.as_str()) && points(l).len() == 2)
        .count();
    // Two pieces and the legend's sample.
    assert_eq!(pieces, 3);
    assert!(plot::render_panels(&[]).contains("<svg"));
}

#[test]
fn log_axes_skip_points_they_cannot_draw() {
    let ring = Marker {
        shape: Shape::Circle,
        radius: 3,
        filled: false,
    };
    let p = Plot {
        title: "log".into(),
        x_label: "frequency f [Hz]".into(),
        y_label: "error [%]".into(),
        x_log: true,
        y_log: true,
        series: vec![
            Series::markers(
                "m",
                vec![
                    (0.05, 1.0),
                    (0.25, 2.0),
                    (1.0, 3.0),
                    (0.0, 4.0),
                    (-1.0, 4.0),
                    (2.0, 0.0),
                    (2.0, -3.0),
                ],
            )
            .with_marker(ring),
        ],
        ..Plot::default()
    };
    let svg = p.render();
    let doc = parse(&svg);
    // Three drawable points and the legend's.
    assert_eq!(elements(&doc, "circle").count(), 4);
    let labels: Vec<&str> = elements(&doc, "text").filter_map(|t| t.text()).collect();
    for tick in ["0.05", "0.1", "0.2", "0.5", "1"] {
        assert!(labels.contains(&tick), "{tick} not in {labels:?}");
    }
}

#[test]
fn the_legend_sits_inside_the_plot_area() {
    let mut p = Plot::new("legend", "time t [s]", "force F [N]");
    // Data in the upper right: the legend goes elsewhere.
    for k in 0..3 {
        p.series.push(Series::line(
            format!("series {k}"),
            (0..200)
                .map(|i| {
                    let x = i as f64 / 200.0;
                    (x, x.powi(8) + 0.01 * f64::from(k))
                })
                .collect(),
        ));
    }
    let svg = p.render();
    let doc = parse(&svg);
    let frame = elements(&doc, "rect")
        .find(|r| r.attribute("fill") == Some("none") && r.attribute("stroke") == Some("#000000"))
        .expect("the plot frame");
    let legend = elements(&doc, "rect")
        .find(|r| r.attribute("opacity") == Some("0.85"))
        .expect("the legend's background");
    let (fx, fy, fw, fh) = (
        attr(&frame, "x"),
        attr(&frame, "y"),
        attr(&frame, "width"),
        attr(&frame, "height"),
    );
    let (lx, ly, lw, lh) = (
        attr(&legend, "x"),
        attr(&legend, "y"),
        attr(&legend, "width"),
        attr(&legend, "height"),
    );
    assert!(lx >= fx && ly >= fy && lx + lw <= fx + fw && ly + lh <= fy + fh);
    assert!(lw < 0.4 * fw, "{lw} of {fw}");
    // Upper left, the emptiest corner.
    assert!(lx < fx + 0.5 * fw && ly < fy + 0.5 * fh, "{lx}, {ly}");
    // A named position, and none.
    p.legend = Legend::LowerRight;
    let doc2 = p.render();
    let doc2 = parse(&doc2);
    let legend = elements(&doc2, "rect")
        .find(|r| r.attribute("opacity") == Some("0.85"))
        .unwrap();
    assert!(attr(&legend, "x") > fx + 0.5 * fw && attr(&legend, "y") > fy + 0.5 * fh);
    p.legend = Legend::Hidden;
    assert!(!p.render().contains("series 0"));
}

#[test]
fn panels_stack_and_output_is_deterministic() {
    let mut a = Plot::new("a", "time t [s]", "force F [N]");
    a.series
        .push(Series::line("a", vec![(0.0, 0.0), (1.0, 2.0)]));
    let mut b = a.clone();
    b.title = "b".into();
    b.series
        .push(Series::dashed("ref", vec![(0.0, 1.0), (1.0, 1.0)]));
    let svg = plot::render_panels(&[a.clone(), b.clone(), a.clone()]);
    let doc = parse(&svg);
    let root = doc.root_element();
    assert_eq!(root.attribute("height"), Some("1680"));
    assert_eq!(svg.matches("<g transform=").count(), 3);
    assert_eq!(svg, plot::render_panels(&[a.clone(), b.clone(), a.clone()]));
    let png = plot::png_panels(&[a.clone(), b.clone()]).unwrap();
    assert_eq!(png, plot::png_panels(&[a.clone(), b.clone()]).unwrap());
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // IHDR: width and height, big-endian.
    assert_eq!(&png[16..24], &[0, 0, 3, 0x20, 0, 0, 4, 0x60]);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.png");
    a.write_png(&path).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), a.png().unwrap());
    let path = dir.path().join("ab.svg");
    plot::write_panels(&[a.clone(), b], &path, Format::Svg).unwrap();
    parse(&std::fs::read_to_string(&path).unwrap());
    let missing = dir.path().join("no/such/dir/a.png");
    assert!(matches!(a.write_png(&missing), Err(PlotError::Io { .. })));
    assert_eq!(Format::Png.extension(), "png");
}

#[test]
fn axis_labels_read_as_given() {
    let mut p = Plot::new("m", "imposed amplitude X [mm]", "modulus K', K'' [N/mm]");
    p.series
        .push(Series::markers("storage K' at 5 Hz", vec![(1.0, 2.0)]));
    let svg = p.render();
    assert!(svg.contains(">modulus K&apos;, K&apos;&apos; [N/mm]</text>"));
    assert!(svg.contains(">imposed amplitude X [mm]</text>"));
    parse(&svg);
}

fn point(f: f64, a: f64, mean: f64, storage: f64, loss: f64) -> ModulusPoint {
    ModulusPoint {
        time_s: 0.0,
        frequency_hz: f,
        amplitude_mm: a,
        mean_mm: mean,
        storage,
        loss,
    }
}

#[test]
fn a_frequency_sweep_plots_against_frequency() {
    let mut pts = Vec::new();
    for mean in [0.0, 1.0] {
        for f in [1.0, 10.0, 50.0] {
            for a in [0.05, 1.0] {
                for k in 0..3 {
                    let s = 100.0 + 10.0 * f64::log10(f) + mean + k as f64;
                    pts.push(point(f, a, mean, s, 0.1 * s * a));
                }
            }
        }
    }
    assert!(probe::sweeps_frequency(&pts));
    let plots = probe::frequency_plots(&pts, "sweep <&>");
    assert_eq!(plots.len(), 6);
    for p in &plots {
        assert!(p.x_log && !p.y_log);
        assert_eq!(p.x_label, "frequency f [Hz]");
        // Per amplitude: the settled line and the markers.
        assert_eq!(p.series.len(), 4);
        assert_eq!(p.series[1].name, "X = 0.05 mm");
        assert_eq!(p.series[3].name, "X = 1 mm");
        assert_eq!(p.series[1].points.len(), 9);
        assert_eq!(p.series[0].points.len(), 3);
    }
    assert!(plots[0].title.contains("mean x 0 mm") && plots[3].title.contains("mean x 1 mm"));
    assert_eq!(plots[1].y_label, "loss modulus K'' [N/mm]");
    assert_eq!(plots[2].y_label, "loss factor K''/K' [-]");
    // The settled value is the last point at each frequency.
    assert_eq!(plots[0].series[0].points[0], (1.0, 102.0));
    let svg = plot::render_panels(&plots);
    parse(&svg);
    assert!(svg.contains(">frequency f [Hz]</text>"));
    // One preload: three panels.
    let one: Vec<ModulusPoint> = pts.iter().copied().filter(|p| p.mean_mm == 0.0).collect();
    assert_eq!(probe::frequency_plots(&one, "t").len(), 3);
    // An amplitude sweep at one frequency is not a frequency sweep.
    let amplitudes: Vec<ModulusPoint> = [0.1, 0.5, 1.0]
        .iter()
        .map(|a| point(5.0, *a, 0.0, 100.0, 10.0))
        .collect();
    assert!(!probe::sweeps_frequency(&amplitudes));
    assert!(!probe::sweeps_frequency(&[]));
    // Two frequencies but each at its own amplitude: not a sweep either.
    let apart = [
        point(1.0, 0.1, 0.0, 1.0, 0.1),
        point(2.0, 0.2, 0.0, 1.0, 0.1),
    ];
    assert!(!probe::sweeps_frequency(&apart));
    // No points: still three well-formed panels that say so.
    let empty = probe::frequency_plots(&[], "t");
    assert_eq!(empty.len(), 3);
    assert!(empty[0].title.contains("no sine"));
    parse(&plot::render_panels(&empty));
}
