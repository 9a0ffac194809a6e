//! Plots as PNG and SVG (plotters): error against the mesh size on log-log axes ([`loglog`]), and
//! curves on linear axes ([`lines`], e.g. force against displacement).
//!
//! Text is drawn by plotters' pure-Rust `ab_glyph` renderer with a TrueType font read from disk
//! at run time (DejaVu Sans from Debian's `fonts-dejavu-core`, which `ci/setup` installs): no
//! fontconfig, no freetype, no network. When no font file is found the plot is still written,
//! without any text (no title, labels, tick values or legend), and [`loglog`] and [`lines`]
//! return a warning saying so.
//!
//! Log axes have ticks of our own (`LogAxis`): plotters' log scale only labels powers of ten,
//! which leaves a convergence study within one decade of h without a single tick. Ticks are taken
//! from the sparsest of the mantissa sets {1}, {1, 2, 5}, {1, ..., 9}, {1, 1.5, ..., 9.5} (times
//! powers of ten) that gives at least three labels in the range (four within a decade); the light
//! grid lines sit at every {1, ..., 9} x 10^k.
//!
//! Linear axes (`LinearAxis`) span the data with a margin of 4 % of its range on each side (any
//! sign), with labelled ticks at the multiples of the smallest step 1, 2 or 5 x 10^k that gives
//! at most 8 (`LINEAR_LABELS`) of them, and light grid lines at a fifth (a quarter for a step
//! 2 x 10^k) of that step.
//!
//! Every series is a line; its points are marked (circle, triangle, square, ... by series), every
//! point for a series of at most 30 (`MARKERS`) points, else every k-th so that about 30 are.
//! In [`lines`] and [`loglog_points`], a series' `flagged` points get a black ring.
//! The legend sits in the corner of the plot that hides the least of the curves. In [`loglog`]
//! it gives every series' least-squares slope of log(error) against log(h) ([`fitted_slope`]),
//! the observed order of convergence; in [`lines`], the series' names.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, KeyPointWeight, Ranged};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::io::output::write_atomic;
use crate::{Error, Result};

/// One curve of a plot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    /// Legend entry (in [`loglog`], the fitted slope is appended).
    pub name: String,
    /// `(x, y)` points, in drawing order: `(h, error)` in [`loglog`], where both must be positive
    /// and finite to appear; in [`lines`], both must be finite.
    pub points: Vec<(f64, f64)>,
    /// Points to flag with a black ring (load steps accepted without convergence, the Pareto
    /// front); [`lines`] and [`loglog_points`].
    pub flagged: Vec<(f64, f64)>,
}

/// Font files tried, in order, for the plot text.
const FONT_FILES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
];

/// The family name the font is registered under (and written into the SVG).
const FAMILY: &str = "sans-serif";

/// The caption's font size: 28 pixels, or less (down to 12) so that a long title fits the
/// width of the plot.
fn caption_size<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, title: &str) -> f64 {
    let width = f64::from(root.dim_in_pixel().0) - 60.0;
    let mut size = 28.0;
    while size > 12.0 {
        match root.estimate_text_size(title, &(FAMILY, size).into_text_style(root)) {
            Ok((w, _)) if f64::from(w) > width => size -= 1.0,
            _ => break,
        }
    }
    size
}

/// At most this many labelled ticks per axis.
const LABELS: usize = 10;

/// At most this many labelled ticks on a linear axis (its labels are longer: `-0.125`).
const LINEAR_LABELS: usize = 8;

/// A series of at most this many points has a marker on every point; a longer one on every k-th
/// point, about this many in all.
const MARKERS: usize = 30;

/// Image size in pixels.
const SIZE: (u32, u32) = (800, 600);

/// Line colours (colour-blind-safe qualitative palette) and marker shapes, by series.
const COLORS: [RGBColor; 6] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(230, 159, 0),
];

/// Registers the first readable font file with plotters, once per process; `None` if none is.
fn font() -> Option<&'static Path> {
    static FONT: OnceLock<Option<&'static Path>> = OnceLock::new();
    *FONT.get_or_init(|| {
        FONT_FILES.iter().map(Path::new).find(|p| {
            let Ok(bytes) = std::fs::read(p) else {
                return false;
            };
            // plotters keeps a 'static reference to the font: the bytes live as long as the
            // process (read once, a few hundred kB).
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font(FAMILY, FontStyle::Normal, bytes).is_ok()
        })
    })
}

/// Writes `<stem>.png` and `<stem>.svg`: log-log axes, one line with markers per series, a
/// legend with each series' fitted slope, the title and the axis labels. Returns warnings
/// (no font found: the plot has no text; points that cannot be shown on log axes).
pub fn loglog(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<Vec<String>> {
    write_loglog(stem, title, x_label, y_label, series, true)
}

/// Writes `<stem>.png` and `<stem>.svg`: linear axes around the data (values of any sign), one
/// line per series (with markers on at most about 30 of its points), a legend with the
/// series' names, the title and the axis labels. Returns warnings (no font found: the plot has no
/// text; non-finite points, which are not shown).
pub fn lines(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<Vec<String>> {
    let mut warnings = font_warnings(stem);
    let plot = Plot::lines(
        title,
        x_label,
        y_label,
        series,
        font().is_some(),
        &mut warnings,
    );
    plot.write(stem)?;
    Ok(warnings)
}

/// Writes `<stem>.png` and `<stem>.svg`: points on log-log axes, one line per series in the
/// given order, a legend with the series' names (no slopes), the `flagged` points ringed (e.g.
/// the Pareto front of error against wall time). Returns warnings as [`loglog`].
pub fn loglog_points(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<Vec<String>> {
    write_loglog(stem, title, x_label, y_label, series, false)
}

/// [`loglog`] (`slopes`: the fitted slopes in the legend) and [`loglog_points`].
fn write_loglog(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    slopes: bool,
) -> Result<Vec<String>> {
    let mut warnings = font_warnings(stem);
    let plot = Plot::new(
        title,
        x_label,
        y_label,
        series,
        slopes,
        font().is_some(),
        &mut warnings,
    );
    plot.write(stem)?;
    Ok(warnings)
}

/// Prints the warnings of a plot writer on stderr, one line each.
pub fn print_warnings(warnings: Vec<String>) {
    for w in warnings {
        crate::error::print_warning(w);
    }
}

/// The warning for a plot at `stem` when no font file is found (none when one is).
fn font_warnings(stem: &Path) -> Vec<String> {
    if font().is_some() {
        return Vec::new();
    }
    vec![format!(
        "no font file found (tried {}; Debian package fonts-dejavu-core): {} has no text",
        FONT_FILES.join(", "),
        with_suffix(stem, "png").display()
    )]
}

/// Least-squares slope of log(y) against log(x): the observed order when y is an error and x a
/// mesh size. Points with a non-positive or non-finite coordinate are ignored; NaN when fewer
/// than two distinct x remain.
pub fn fitted_slope(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|&&(x, y)| loggable(x) && loggable(y))
        .map(|&(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return f64::NAN;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    if sxx > 0.0 {
        sxy / sxx
    } else {
        f64::NAN
    }
}

/// True if `v` can be placed on a log axis.
fn loggable(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// `stem` with `.ext` appended to its file name (a stem may itself contain dots).
fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut name = stem.file_name().unwrap_or_default().to_os_string();
    name.push(".");
    name.push(ext);
    stem.with_file_name(name)
}

/// What the plots need of an axis kind ([`LogAxis`], [`LinearAxis`]) beyond plotters' mapping.
trait Axis: Ranged<ValueType = f64, FormatOption = DefaultFormatting> + Clone + 'static {
    /// What a coordinate must be to be shown, for warnings ("finite").
    const SHOWN: &'static str;

    /// True if the coordinate `v` can be placed on this kind of axis.
    fn shows(v: f64) -> bool;

    /// The label of the tick at `v`.
    fn label(&self, v: f64) -> String;
}

/// A plot ready to draw on any backend, on axes of kind `A`.
struct Plot<'a, A: Axis> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    /// Legend entries and the points that can be shown.
    curves: Vec<(String, Vec<(f64, f64)>)>,
    /// Points to cross out (finite ones of every series' `flagged`).
    flagged: Vec<(f64, f64)>,
    x: A,
    y: A,
    text: bool,
}

impl<'a> Plot<'a, LogAxis> {
    /// A log-log plot: with `slopes`, the legend gives each series' fitted slope.
    fn new(
        title: &'a str,
        x_label: &'a str,
        y_label: &'a str,
        series: &[Series],
        slopes: bool,
        text: bool,
        warnings: &mut Vec<String>,
    ) -> Plot<'a, LogAxis> {
        let curves: Vec<(String, Vec<(f64, f64)>)> = shown::<LogAxis>(title, series, warnings)
            .into_iter()
            .map(|(name, shown)| {
                let slope = fitted_slope(&shown);
                let entry = match shown.len() {
                    0 => format!("{name}: no points"),
                    _ if slopes && slope.is_finite() => format!("{name}: slope {slope:.2}"),
                    _ => name.to_string(),
                };
                (entry, shown)
            })
            .collect();
        let all: Vec<(f64, f64)> = curves.iter().flat_map(|c| c.1.iter().copied()).collect();
        let x = LogAxis::around(all.iter().map(|p| p.0), 0.08, (0.1, 1.0));
        let y = LogAxis::around(all.iter().map(|p| p.1), 0.12, (0.01, 1.0));
        let flagged = series
            .iter()
            .flat_map(|s| s.flagged.iter().copied())
            .filter(|&(x, y)| LogAxis::shows(x) && LogAxis::shows(y))
            .collect();
        Plot {
            title,
            x_label,
            y_label,
            curves,
            flagged,
            x,
            y,
            text,
        }
    }
}

impl<'a> Plot<'a, LinearAxis> {
    /// A plot on linear axes: the legend gives the series' names.
    fn lines(
        title: &'a str,
        x_label: &'a str,
        y_label: &'a str,
        series: &[Series],
        text: bool,
        warnings: &mut Vec<String>,
    ) -> Plot<'a, LinearAxis> {
        let curves: Vec<(String, Vec<(f64, f64)>)> = shown::<LinearAxis>(title, series, warnings)
            .into_iter()
            .map(|(name, shown)| {
                let entry = match shown.len() {
                    0 => format!("{name}: no points"),
                    _ => name.to_string(),
                };
                (entry, shown)
            })
            .collect();
        let all: Vec<(f64, f64)> = curves.iter().flat_map(|c| c.1.iter().copied()).collect();
        let x = LinearAxis::around(all.iter().map(|p| p.0), 0.04, (0.0, 1.0));
        let y = LinearAxis::around(all.iter().map(|p| p.1), 0.04, (0.0, 1.0));
        let flagged = series
            .iter()
            .flat_map(|s| s.flagged.iter().copied())
            .filter(|&(x, y)| LinearAxis::shows(x) && LinearAxis::shows(y))
            .collect();
        Plot {
            title,
            x_label,
            y_label,
            curves,
            flagged,
            x,
            y,
            text,
        }
    }
}

/// Every series' name and the points that axes of kind `A` can show; a warning per series that
/// loses points.
fn shown<'s, A: Axis>(
    title: &str,
    series: &'s [Series],
    warnings: &mut Vec<String>,
) -> Vec<(&'s str, Vec<(f64, f64)>)> {
    series
        .iter()
        .map(|s| {
            let shown: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|&(x, y)| A::shows(x) && A::shows(y))
                .collect();
            if shown.len() < s.points.len() {
                warnings.push(format!(
                    "plot '{title}': {} point(s) of '{}' are not {} and are not shown",
                    s.points.len() - shown.len(),
                    s.name,
                    A::SHOWN
                ));
            }
            (s.name.as_str(), shown)
        })
        .collect()
}

impl<A: Axis> Plot<'_, A> {
    /// Writes `<stem>.png` and `<stem>.svg`, each atomically.
    fn write(&self, stem: &Path) -> Result<()> {
        let png = with_suffix(stem, "png");
        let svg = with_suffix(stem, "svg");

        let mut svg_text = String::new();
        {
            let root = SVGBackend::with_string(&mut svg_text, SIZE).into_drawing_area();
            self.draw(&root).map_err(|e| {
                Error::Other(format!("{}: cannot draw the plot: {e}", svg.display()))
            })?;
        }
        write_atomic(&svg, svg_text.as_bytes())?;

        // The bitmap backend encodes the PNG into a file named by extension: draw into a
        // temporary file beside the target, then publish its bytes atomically.
        let tmp = with_suffix(
            &stem.with_file_name(format!(
                ".{}.{}",
                png.file_name().unwrap_or_default().to_string_lossy(),
                std::process::id()
            )),
            "png",
        );
        let drawn = (|| -> std::result::Result<Vec<u8>, String> {
            {
                let root = BitMapBackend::new(&tmp, SIZE).into_drawing_area();
                self.draw(&root)?;
            }
            std::fs::read(&tmp).map_err(|e| e.to_string())
        })();
        let _ = std::fs::remove_file(&tmp);
        let bytes = drawn
            .map_err(|e| Error::Other(format!("{}: cannot draw the plot: {e}", png.display())))?;
        write_atomic(&png, &bytes)
    }

    /// Draws the plot on `root` and presents it.
    ///
    /// Markers and the legend are drawn in pixels on `root` with elements that do not carry the
    /// backend type: plotters' composed elements do, and its series and legend bounds then
    /// demand a `'static` backend, which one writing to a borrowed path or string is not.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let mut builder = ChartBuilder::on(root);
        builder.margin(20).margin_right(30);
        if self.text {
            builder
                .caption(self.title, (FAMILY, caption_size(root, self.title)))
                .x_label_area_size(60)
                .y_label_area_size(85);
        }
        let mut chart = builder
            .build_cartesian_2d(self.x.clone(), self.y.clone())
            .map_err(e)?;

        let x_fmt = |v: &f64| self.x.label(*v);
        let y_fmt = |v: &f64| self.y.label(*v);
        let mut mesh = chart.configure_mesh();
        mesh.x_labels(LABELS)
            .y_labels(LABELS)
            .max_light_lines(9)
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(200, 200, 200))
            .axis_style(BLACK.stroke_width(1));
        if self.text {
            mesh.x_desc(self.x_label)
                .y_desc(self.y_label)
                .x_label_formatter(&x_fmt)
                .y_label_formatter(&y_fmt)
                .label_style((FAMILY, 18))
                .axis_desc_style((FAMILY, 20));
        }
        mesh.draw().map_err(e)?;

        // The frame (without text the axes above are not drawn).
        let (xr, yr) = (self.x.range(), self.y.range());
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![
                    (xr.start, yr.start),
                    (xr.end, yr.start),
                    (xr.end, yr.end),
                    (xr.start, yr.end),
                    (xr.start, yr.start),
                ],
                BLACK.stroke_width(1),
            )))
            .map_err(e)?;

        for (i, (_, points)) in self.curves.iter().enumerate() {
            let color = COLORS[i % COLORS.len()];
            chart
                .draw_series(std::iter::once(PathElement::new(
                    points.clone(),
                    color.stroke_width(2),
                )))
                .map_err(e)?;
            for p in points.iter().step_by(marker_every(points.len())) {
                marker(root, i, chart.backend_coord(p), color).map_err(e)?;
            }
        }
        for p in &self.flagged {
            ring(root, chart.backend_coord(p)).map_err(e)?;
        }
        if self.text && !self.curves.is_empty() {
            let pixels: Vec<Vec<(i32, i32)>> = self
                .curves
                .iter()
                .map(|(_, pts)| pts.iter().map(|p| chart.backend_coord(p)).collect())
                .collect();
            self.legend(root, chart.plotting_area().get_pixel_range(), &pixels)
                .map_err(e)?;
        }
        root.present().map_err(e)
    }

    /// The legend: per series a line with its marker, then its entry (name, slope), in a box in the
    /// corner of the plotting area `plot` (pixels) that hides the least of the curves (`pixels`).
    fn legend<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        plot: (Range<i32>, Range<i32>),
        pixels: &[Vec<(i32, i32)>],
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let style =
            TextStyle::from((FAMILY, 18).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        let (pad, line_w, row_h) = (12, 36, 28);
        let mut text_w = 0;
        for (entry, _) in &self.curves {
            text_w = text_w.max(root.estimate_text_size(entry, &style)?.0 as i32);
        }
        let w = pad + line_w + 10 + text_w + pad;
        let h = pad + row_h * self.curves.len() as i32 + pad - 8;
        let (x0, y0) = legend_corner(plot, (w, h), pixels);
        let (x1, y1) = (x0 + w, y0 + h);
        root.draw(&Rectangle::new(
            [(x0, y0), (x1, y1)],
            WHITE.mix(0.92).filled(),
        ))?;
        root.draw(&Rectangle::new(
            [(x0, y0), (x1, y1)],
            RGBColor(120, 120, 120),
        ))?;
        for (i, (entry, _)) in self.curves.iter().enumerate() {
            let color = COLORS[i % COLORS.len()];
            let y = y0 + pad + row_h / 2 - 4 + row_h * i as i32;
            let x = x0 + pad;
            root.draw(&PathElement::new(
                vec![(x, y), (x + line_w, y)],
                color.stroke_width(2),
            ))?;
            marker(root, i, (x + line_w / 2, y), color)?;
            root.draw(&Text::new(
                entry.clone(),
                (x + line_w + 10, y),
                style.clone(),
            ))?;
        }
        Ok(())
    }
}

/// Markers go on every this many points of a series of `n` points (see [`MARKERS`]).
fn marker_every(n: usize) -> usize {
    n.div_ceil(MARKERS).max(1)
}

/// The upper left pixel of a `size` box in one corner of `plot` (lower right, upper left, lower
/// left, upper right: the first that covers the fewest samples of the `curves`).
fn legend_corner(
    (px, py): (Range<i32>, Range<i32>),
    (w, h): (i32, i32),
    curves: &[Vec<(i32, i32)>],
) -> (i32, i32) {
    const INSET: i32 = 12;
    let (left, right) = (px.start + INSET, px.end - INSET - w);
    let (top, bottom) = (py.start + INSET, py.end - INSET - h);
    let mut samples = Vec::new();
    for c in curves {
        samples.extend(c.iter().map(|&(x, y)| (f64::from(x), f64::from(y))));
        for s in c.windows(2) {
            let (a, b) = (s[0], s[1]);
            for k in 1..32 {
                let t = f64::from(k) / 32.0;
                samples.push((
                    f64::from(a.0) + t * f64::from(b.0 - a.0),
                    f64::from(a.1) + t * f64::from(b.1 - a.1),
                ));
            }
        }
    }
    let covered = |(x0, y0): (i32, i32)| {
        let m = 8.0; // markers have a size
        let (x0, y0) = (f64::from(x0) - m, f64::from(y0) - m);
        let (x1, y1) = (x0 + f64::from(w) + 2.0 * m, y0 + f64::from(h) + 2.0 * m);
        samples
            .iter()
            .filter(|&&(x, y)| x >= x0 && x <= x1 && y >= y0 && y <= y1)
            .count()
    };
    let corners = [(right, bottom), (left, top), (left, bottom), (right, top)];
    let mut best = corners[0];
    let mut least = usize::MAX;
    for c in corners {
        let n = covered(c);
        if n < least {
            best = c;
            least = n;
        }
    }
    best
}

/// A black ring around a flagged point at pixel `at` (larger than any series marker, and
/// unlike them not filled).
fn ring<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    at: (i32, i32),
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.draw(&Circle::new(at, 10, BLACK.stroke_width(2)))
}

/// Marker `shape` (circle, triangle, square, diamond, cross, by series) at pixel `at`.
fn marker<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    shape: usize,
    (x, y): (i32, i32),
    color: RGBColor,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    const S: i32 = 6;
    let fill = color.filled();
    match shape % 5 {
        0 => root.draw(&Circle::new((x, y), S, fill)),
        1 => root.draw(&Polygon::new(
            vec![(x, y - S - 1), (x + S + 1, y + S), (x - S - 1, y + S)],
            fill,
        )),
        2 => root.draw(&Rectangle::new(
            [(x - S + 1, y - S + 1), (x + S - 1, y + S - 1)],
            fill,
        )),
        3 => root.draw(&Polygon::new(
            vec![
                (x, y - S - 1),
                (x + S + 1, y),
                (x, y + S + 1),
                (x - S - 1, y),
            ],
            fill,
        )),
        _ => {
            let pen = color.stroke_width(3);
            root.draw(&PathElement::new(vec![(x - S, y - S), (x + S, y + S)], pen))?;
            root.draw(&PathElement::new(vec![(x - S, y + S), (x + S, y - S)], pen))
        }
    }
}

/// A logarithmic axis over `[lo, hi]` with ticks at "nice" mantissas (see the module docs).
#[derive(Clone, Debug)]
struct LogAxis {
    lo: f64,
    hi: f64,
}

impl LogAxis {
    /// The range of `values` (positive), widened by `pad` of its log-length on each side (at
    /// least a factor 1.1), then out to the next labelled tick at either end unless that
    /// widens it by more than 15 % of its log-length; `empty` without values.
    fn around(values: impl Iterator<Item = f64>, pad: f64, empty: (f64, f64)) -> LogAxis {
        let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        if !(lo.is_finite() && hi >= lo) {
            return LogAxis {
                lo: empty.0,
                hi: empty.1,
            };
        }
        let factor = ((hi / lo).ln() * pad).exp().max(1.1);
        let padded = LogAxis {
            lo: lo / factor,
            hi: hi * factor,
        };
        let set = padded.label_set(LABELS);
        let length = (padded.hi / padded.lo).ln();
        let below = LogAxis {
            lo: padded.lo / 10.0,
            hi: padded.lo,
        }
        .ticks(set)
        .last()
        .copied()
        .filter(|&t| (padded.lo / t).ln() <= 0.15 * length);
        let above = LogAxis {
            lo: padded.hi,
            hi: padded.hi * 10.0,
        }
        .ticks(set)
        .first()
        .copied()
        .filter(|&t| (t / padded.hi).ln() <= 0.15 * length);
        LogAxis {
            lo: below.unwrap_or(padded.lo),
            hi: above.unwrap_or(padded.hi),
        }
    }

    /// Tick values `m 10^k` in range for the mantissas `set`.
    fn ticks(&self, set: &[f64]) -> Vec<f64> {
        let (k0, k1) = (
            self.lo.log10().floor() as i32,
            self.hi.log10().ceil() as i32,
        );
        let mut out = Vec::new();
        for k in k0..=k1 {
            for &m in set {
                // m / 10^-k is exact for the decimal mantissas where m * 10^k is not.
                let v = if k < 0 {
                    m / 10f64.powi(-k)
                } else {
                    m * 10f64.powi(k)
                };
                if v >= self.lo * (1.0 - 1e-12) && v <= self.hi * (1.0 + 1e-12) {
                    out.push(v);
                }
            }
        }
        out
    }

    /// The mantissas of the labelled ticks: the sparsest set with at least 3 ticks in range (4
    /// within a decade) and at most `max`.
    fn label_set(&self, max: usize) -> &'static [f64] {
        const SETS: [&[f64]; 4] = [
            &[1.0],
            &[1.0, 2.0, 5.0],
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
            &[
                1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.5, 6.0, 6.5, 7.0, 7.5, 8.0, 8.5,
                9.0, 9.5,
            ],
        ];
        let least = if self.hi / self.lo < 10.0 { 4 } else { 3 };
        let mut best = SETS[0];
        for set in SETS {
            let n = self.ticks(set).len();
            if n > max {
                break;
            }
            best = set;
            if n >= least {
                break;
            }
        }
        best
    }

    /// The labelled ticks (see [`LogAxis::label_set`]; over more than `max` decades, every
    /// few powers of ten).
    fn bold_ticks(&self, max: usize) -> Vec<f64> {
        let t = self.ticks(self.label_set(max));
        let every = t.len().div_ceil(max.max(1)).max(1);
        t.into_iter().step_by(every).collect()
    }
}

impl Ranged for LogAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let s = (value.ln() - self.lo.ln()) / (self.hi.ln() - self.lo.ln());
        limit.0 + (s * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        let max = hint.max_num_points();
        match hint.weight() {
            KeyPointWeight::Bold => self.bold_ticks(max),
            KeyPointWeight::Any => {
                let all = self.ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
                if all.len() <= max {
                    all
                } else {
                    self.ticks(&[1.0])
                }
            }
        }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl Axis for LogAxis {
    const SHOWN: &'static str = "positive and finite";

    fn shows(v: f64) -> bool {
        loggable(v)
    }

    fn label(&self, v: f64) -> String {
        tick_label(v)
    }
}

/// A linear axis over `[lo, hi]` with ticks at the multiples of a round step (see the module
/// docs).
#[derive(Clone, Debug)]
struct LinearAxis {
    lo: f64,
    hi: f64,
}

/// A tick step `m 10^e`, `m` in {1, 2, 5}.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Step {
    m: i64,
    e: i32,
}

impl Step {
    /// `k` steps: `k m 10^e`, computed as `k m / 10^-e` for a negative `e` (exact for the
    /// decimal ticks where a product with 10^e is not).
    fn times(self, k: i64) -> f64 {
        let km = (k * self.m) as f64;
        if self.e < 0 {
            km / 10f64.powi(-self.e)
        } else {
            km * 10f64.powi(self.e)
        }
    }

    /// The next larger step: 1 -> 2 -> 5 -> 10.
    fn next(self) -> Step {
        match self.m {
            1 => Step { m: 2, e: self.e },
            2 => Step { m: 5, e: self.e },
            _ => Step {
                m: 1,
                e: self.e + 1,
            },
        }
    }

    /// The light-line step: a fifth of a step 1 or 5 x 10^e, a quarter of a step 2 x 10^e.
    fn minor(self) -> Step {
        match self.m {
            1 => Step {
                m: 2,
                e: self.e - 1,
            },
            2 => Step {
                m: 5,
                e: self.e - 1,
            },
            _ => Step { m: 1, e: self.e },
        }
    }
}

impl LinearAxis {
    /// The range of the finite `values`, widened by `pad` of its length on each side (a single
    /// value `v`: `v -/+ 10 %` of `|v|`, or `-/+ 1` for zero); `empty` without values.
    fn around(values: impl Iterator<Item = f64>, pad: f64, empty: (f64, f64)) -> LinearAxis {
        let (lo, hi) = values
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        if !(lo.is_finite() && hi.is_finite()) {
            return LinearAxis {
                lo: empty.0,
                hi: empty.1,
            };
        }
        if hi == lo {
            let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
            return LinearAxis {
                lo: lo - d,
                hi: hi + d,
            };
        }
        let m = pad * (hi - lo);
        LinearAxis {
            lo: lo - m,
            hi: hi + m,
        }
    }

    /// The smallest round step with at most `max` (at least 2) ticks in range.
    fn tick_step(&self, max: usize) -> Step {
        let max = max.max(2);
        let len = self.hi - self.lo;
        if !(len > 0.0 && len.is_finite()) {
            return Step { m: 1, e: 0 };
        }
        // A step of a tenth of len / max has too many ticks: start there and grow.
        let mut step = Step {
            m: 1,
            e: (len / max as f64).log10().floor() as i32 - 1,
        };
        while self.count(step) > max {
            step = step.next();
        }
        step
    }

    /// How many multiples of `step` are in range.
    fn count(&self, step: Step) -> usize {
        let (k0, k1) = self.bounds(step);
        usize::try_from(k1 - k0 + 1).unwrap_or(0)
    }

    /// The first and last multiple of `step` in range, as multipliers.
    fn bounds(&self, step: Step) -> (i64, i64) {
        let s = step.times(1);
        let slack = 1e-9;
        (
            (self.lo / s - slack).ceil() as i64,
            (self.hi / s + slack).floor() as i64,
        )
    }

    /// The multiples of `step` in range.
    fn ticks(&self, step: Step) -> Vec<f64> {
        let (k0, k1) = self.bounds(step);
        (k0..=k1).map(|k| step.times(k)).collect()
    }
}

impl Ranged for LinearAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let s = (value - self.lo) / (self.hi - self.lo);
        limit.0 + (s * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        let max = hint.max_num_points();
        let step = self.tick_step(max.min(LINEAR_LABELS));
        match hint.weight() {
            KeyPointWeight::Bold => self.ticks(step),
            KeyPointWeight::Any => {
                let minor = self.ticks(step.minor());
                if minor.len() <= max {
                    minor
                } else {
                    self.ticks(step)
                }
            }
        }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl Axis for LinearAxis {
    const SHOWN: &'static str = "finite";

    fn shows(v: f64) -> bool {
        v.is_finite()
    }

    fn label(&self, v: f64) -> String {
        linear_label(v, self.tick_step(LINEAR_LABELS))
    }
}

/// A tick value of a linear axis with labels every `step`: as many decimals as the step has
/// (`-0.15`, `0.10`, `40`), or in scientific notation with the step's digits when the step is
/// below 10^-4 or above 10^4 or the value is 10^6 or more (`1.25e-5`, `2.4e6`).
fn linear_label(v: f64, step: Step) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{}", if v == 0.0 { 0.0 } else { v });
    }
    if (-4..=4).contains(&step.e) && v.abs() < 1e6 {
        let decimals = (-step.e).max(0) as usize;
        return format!("{v:.decimals$}");
    }
    let e = v.abs().log10().floor() as i32;
    let digits = (e - step.e).max(0) as usize;
    let m = v / 10f64.powi(e);
    format!("{}e{e}", trim_zeros(format!("{m:.digits$}")))
}

/// A tick value in at most 3 significant digits: `0.25`, `40`, `2e-5`, `1.5e6`.
fn tick_label(v: f64) -> String {
    if !loggable(v) {
        return format!("{v}");
    }
    let e = v.log10().floor() as i32;
    if (-3..4).contains(&e) {
        let decimals = (2 - e).max(0) as usize;
        trim_zeros(format!("{v:.decimals$}"))
    } else {
        let m = v / 10f64.powi(e);
        format!("{}e{e}", trim_zeros(format!("{m:.2}")))
    }
}

/// `"0.2500"` -> `"0.25"`, `"3.00"` -> `"3"`.
fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A short title keeps the 28-pixel caption; a long one (a study's Pareto title) is set
    /// smaller, so that it fits the width of the plot.
    #[test]
    fn a_long_caption_is_set_smaller_to_fit() {
        if font().is_none() {
            return; // no font on this machine: plots have no text
        }
        let mut svg = String::new();
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        assert_eq!(caption_size(&root, "Hertz"), 28.0);
        let long = "study_solver: curve_max_rel_diff to reference against wall time (ringed: \
                    Pareto front)";
        let size = caption_size(&root, long);
        assert!((12.0..28.0).contains(&size), "{size}");
        let style = (FAMILY, size).into_text_style(&root);
        let (w, _) = root.estimate_text_size(long, &style).unwrap();
        assert!(f64::from(w) <= f64::from(SIZE.0) - 60.0, "{w}");
    }

    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<(f64, f64)> = [0.5, 0.25, 0.125, 0.1]
            .iter()
            .map(|&h: &f64| (h, 3.0 * h.powf(1.7)))
            .collect();
        assert!((fitted_slope(&pts) - 1.7).abs() < 1e-12);
        assert!(fitted_slope(&pts[..1]).is_nan());
        assert!(fitted_slope(&[(0.5, 1.0), (0.5, 2.0)]).is_nan());
        // Unusable points are ignored.
        let mut with_bad = pts.clone();
        with_bad.push((0.2, 0.0));
        with_bad.push((f64::NAN, 1.0));
        assert!((fitted_slope(&with_bad) - 1.7).abs() < 1e-12);
    }

    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(0.25), "0.25");
        assert_eq!(tick_label(0.3), "0.3");
        assert_eq!(tick_label(1.0), "1");
        assert_eq!(tick_label(40.0), "40");
        assert_eq!(tick_label(0.002), "0.002");
        assert_eq!(tick_label(2e-5), "2e-5");
        assert_eq!(tick_label(1.5e6), "1.5e6");
    }

    #[test]
    fn log_ticks_are_nice_and_never_too_few() {
        // Within one decade: 1..9 mantissas, or halves.
        let a = LogAxis { lo: 0.15, hi: 0.56 };
        assert_eq!(a.bold_ticks(10), vec![0.2, 0.3, 0.4, 0.5]);
        let a = LogAxis { lo: 0.23, hi: 0.54 };
        assert_eq!(a.bold_ticks(10), vec![0.25, 0.3, 0.35, 0.4, 0.45, 0.5]);
        // Several decades: powers of ten.
        let a = LogAxis { lo: 3e-4, hi: 0.2 };
        assert_eq!(a.bold_ticks(10), vec![1e-3, 1e-2, 0.1]);
        // Two decades: 1, 2, 5.
        let a = LogAxis {
            lo: 0.004,
            hi: 0.15,
        };
        assert_eq!(a.bold_ticks(10), vec![0.005, 0.01, 0.02, 0.05, 0.1]);
        // Many decades: every other power.
        let a = LogAxis { lo: 1e-15, hi: 1e3 };
        assert_eq!(a.bold_ticks(10).len(), 10);
    }

    #[test]
    fn axis_ends_at_labelled_ticks_when_close() {
        let a = LogAxis::around([0.0325, 0.35].into_iter(), 0.12, (1.0, 2.0));
        assert_eq!((a.lo, a.hi), (0.02, 0.5));
        let a = LogAxis::around([0.25, 0.5].into_iter(), 0.08, (1.0, 2.0));
        assert_eq!((a.lo, a.hi), (0.2, 0.55));
        // Far from a tick (here a power of ten): only padded.
        let a = LogAxis::around([4e-4, 0.25].into_iter(), 0.02, (1.0, 2.0));
        assert!(
            a.lo > 1e-4 && a.lo < 4e-4 && a.hi > 0.25 && a.hi < 1.0,
            "{a:?}"
        );
        let a = LogAxis::around(std::iter::empty(), 0.1, (0.1, 1.0));
        assert_eq!((a.lo, a.hi), (0.1, 1.0));
    }

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("mortar-plot-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn sample() -> Vec<Series> {
        let hs = [0.5, 1.0 / 3.0, 0.25];
        vec![
            Series {
                name: "hex8".into(),
                points: hs.iter().map(|&h| (h, 0.3 * h)).collect(),
                ..Default::default()
            },
            Series {
                name: "hex20".into(),
                points: hs.iter().map(|&h| (h, 0.1 * h * h)).collect(),
                ..Default::default()
            },
        ]
    }

    #[test]
    fn plot_files_are_written() {
        let dir = scratch("files");
        let stem = dir.join("convergence");
        let warnings = loglog(&stem, "Title", "h", "error", &sample()).unwrap();
        let png = std::fs::read(dir.join("convergence.png")).unwrap();
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
        let svg = std::fs::read_to_string(dir.join("convergence.svg")).unwrap();
        assert!(svg.contains("<svg"));
        if font().is_some() {
            assert!(warnings.is_empty(), "{warnings:?}");
            assert!(svg.contains("slope 2.00"), "legend missing");
        }
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["convergence.png", "convergence.svg"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn plot_without_font_has_no_text() {
        let dir = scratch("nofont");
        let mut warnings = Vec::new();
        let plot = Plot::new("T", "h", "e", &sample(), true, false, &mut warnings);
        plot.write(&dir.join("c")).unwrap();
        assert!(warnings.is_empty());
        let svg = std::fs::read_to_string(dir.join("c.svg")).unwrap();
        assert!(!svg.contains("<text"));
        assert!(std::fs::metadata(dir.join("c.png")).unwrap().len() > 100);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn bad_points_are_skipped_with_a_warning() {
        let dir = scratch("bad");
        let s = vec![Series {
            name: "x".into(),
            points: vec![(0.5, 0.1), (0.25, f64::NAN), (0.0, 1.0)],
            ..Default::default()
        }];
        let w = loglog(&dir.join("c"), "T", "h", "e", &s).unwrap();
        assert!(w.iter().any(|w| w.contains("2 point(s) of 'x'")), "{w:?}");
        let empty = loglog(&dir.join("d"), "T", "h", "e", &[]).unwrap();
        assert!(empty.iter().all(|w| w.contains("font")));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn linear_ticks_are_round() {
        // [0, 0.5] with a margin: steps of 0.1 (0.05 would give 11 labels).
        let a = LinearAxis::around([0.0, 0.5].into_iter(), 0.04, (0.0, 1.0));
        assert!(
            (a.lo + 0.02).abs() < 1e-12 && (a.hi - 0.52).abs() < 1e-12,
            "{a:?}"
        );
        let step = a.tick_step(LINEAR_LABELS);
        assert_eq!(step, Step { m: 1, e: -1 });
        assert_eq!(a.ticks(step), vec![0.0, 0.1, 0.2, 0.3, 0.4, 0.5]);
        assert_eq!(a.key_points(LINEAR_LABELS), a.ticks(step));
        // Light lines every fifth of a step.
        assert_eq!(a.ticks(step.minor()).len(), 28);
        // Other spans: steps 2 and 5 x 10^k.
        let a = LinearAxis { lo: 0.0, hi: 13.0 };
        assert_eq!(
            a.ticks(a.tick_step(8)),
            vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0]
        );
        let a = LinearAxis {
            lo: 0.003,
            hi: 0.031,
        };
        assert_eq!(
            a.ticks(a.tick_step(8)),
            vec![0.005, 0.01, 0.015, 0.02, 0.025, 0.03]
        );
        // Pixels: the ends of the range map to the ends of the axis.
        let a = LinearAxis { lo: -2.0, hi: 2.0 };
        assert_eq!((a.map(&-2.0, (0, 400)), a.map(&0.0, (0, 400))), (0, 200));
        assert_eq!(a.map(&2.0, (0, 400)), 400);
    }

    #[test]
    fn linear_axes_take_negative_and_degenerate_ranges() {
        // A compressive reaction: all negative.
        let a = LinearAxis::around([-48.0, -5.2, -20.0].into_iter(), 0.04, (0.0, 1.0));
        assert!(a.lo < -48.0 && a.hi > -5.2 && a.hi < 0.0, "{a:?}");
        let step = a.tick_step(LINEAR_LABELS);
        assert_eq!(a.ticks(step), vec![-40.0, -30.0, -20.0, -10.0]);
        let labels: Vec<String> = a.ticks(step).iter().map(|&v| a.label(v)).collect();
        assert_eq!(labels, ["-40", "-30", "-20", "-10"]);
        // Across zero: zero is a tick, labelled "0".
        let a = LinearAxis::around([-0.2, 0.05].into_iter(), 0.04, (0.0, 1.0));
        let ticks = a.ticks(a.tick_step(LINEAR_LABELS));
        assert_eq!(ticks, vec![-0.2, -0.15, -0.1, -0.05, 0.0, 0.05]);
        let labels: Vec<String> = ticks.iter().map(|&v| a.label(v)).collect();
        assert_eq!(labels, ["-0.20", "-0.15", "-0.10", "-0.05", "0", "0.05"]);
        // One value, zero, none: a range around it, or the default.
        let a = LinearAxis::around([3.0, 3.0].into_iter(), 0.04, (0.0, 1.0));
        assert_eq!((a.lo, a.hi), (2.7, 3.3));
        let a = LinearAxis::around([0.0].into_iter(), 0.04, (0.0, 1.0));
        assert_eq!((a.lo, a.hi), (-1.0, 1.0));
        let a = LinearAxis::around([f64::NAN].into_iter(), 0.04, (0.0, 1.0));
        assert_eq!((a.lo, a.hi), (0.0, 1.0));
    }

    #[test]
    fn linear_labels() {
        let step = |m, e| Step { m, e };
        assert_eq!(linear_label(0.15, step(5, -2)), "0.15");
        assert_eq!(linear_label(0.1, step(5, -2)), "0.10");
        assert_eq!(linear_label(-40.0, step(1, 1)), "-40");
        assert_eq!(linear_label(0.0, step(1, -1)), "0");
        assert_eq!(linear_label(-0.0, step(1, -1)), "0");
        assert_eq!(linear_label(2500.0, step(5, 2)), "2500");
        assert_eq!(linear_label(2.5e-5, step(5, -6)), "2.5e-5");
        assert_eq!(linear_label(-1.2e6, step(2, 5)), "-1.2e6");
        assert_eq!(linear_label(3e7, step(1, 7)), "3e7");
    }

    #[test]
    fn markers_on_at_most_about_thirty_points() {
        assert_eq!(marker_every(0), 1);
        assert_eq!(marker_every(5), 1);
        assert_eq!(marker_every(30), 1);
        assert_eq!(marker_every(31), 2);
        assert_eq!(marker_every(300), 10);
        // 300 points: 30 markers (circles, the first series' shape), plus the legend's.
        let dir = scratch("markers");
        let s = vec![Series {
            name: "many".into(),
            points: (0..300)
                .map(|i| (f64::from(i), f64::from(i).sin()))
                .collect(),
            ..Default::default()
        }];
        lines(&dir.join("m"), "T", "x", "y", &s).unwrap();
        let svg = std::fs::read_to_string(dir.join("m.svg")).unwrap();
        let circles = svg.matches("<circle").count();
        let legend = usize::from(font().is_some());
        assert_eq!(circles, 30 + legend, "{circles} circles");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn line_plot_files_are_written() {
        let dir = scratch("lines");
        let stem = dir.join("curves");
        let series = vec![
            Series {
                name: "soft".into(),
                points: (0..=4)
                    .map(|i| (-0.05 * f64::from(i), -12.0 * f64::from(i)))
                    .collect(),
                ..Default::default()
            },
            Series {
                name: "stiff".into(),
                points: (0..=4)
                    .map(|i| (-0.05 * f64::from(i), -24.0 * f64::from(i)))
                    .collect(),
                flagged: vec![(-0.1, -48.0)],
            },
            Series {
                name: "failed".into(),
                points: vec![],
                ..Default::default()
            },
        ];
        let warnings = lines(&stem, "Reaction", "u_z", "reaction", &series).unwrap();
        let png = std::fs::read(dir.join("curves.png")).unwrap();
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
        let svg = std::fs::read_to_string(dir.join("curves.svg")).unwrap();
        assert!(svg.contains("<svg"));
        if font().is_some() {
            assert!(warnings.is_empty(), "{warnings:?}");
            for text in [
                "soft",
                "stiff",
                "failed: no points",
                "Reaction",
                "-0.20",
                "-80",
            ] {
                assert!(svg.contains(&format!("\n{text}\n")), "no {text} in the SVG");
            }
            assert!(!svg.contains("slope"));
        } else {
            assert!(warnings[0].contains("no font"), "{warnings:?}");
        }
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["curves.png", "curves.svg"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn line_plot_drops_non_finite_points_with_a_warning() {
        let dir = scratch("lines-bad");
        let s = vec![
            Series {
                name: "x".into(),
                points: vec![
                    (0.0, 1.0),
                    (0.5, f64::NAN),
                    (f64::INFINITY, 2.0),
                    (-1.0, -3.0),
                ],
                ..Default::default()
            },
            Series {
                name: "negative".into(),
                points: vec![(-1.0, -1.0), (-2.0, -5.0)],
                ..Default::default()
            },
        ];
        let w = lines(&dir.join("c"), "T", "x", "y", &s).unwrap();
        let dropped: Vec<&String> = w.iter().filter(|w| w.contains("point(s)")).collect();
        assert_eq!(dropped.len(), 1, "{w:?}");
        assert!(
            dropped[0].contains("2 point(s) of 'x' are not finite"),
            "{w:?}"
        );
        let mut warnings = Vec::new();
        let plot = Plot::lines("T", "x", "y", &s, false, &mut warnings);
        assert_eq!(plot.curves[0].1, vec![(0.0, 1.0), (-1.0, -3.0)]);
        assert_eq!(plot.curves[1].1, s[1].points);
        assert!(plot.x.lo < -2.0 && plot.x.hi > 0.0 && plot.y.lo < -5.0 && plot.y.hi > 1.0);
        plot.write(&dir.join("d")).unwrap();
        let svg = std::fs::read_to_string(dir.join("d.svg")).unwrap();
        assert!(!svg.contains("<text"));
        let empty = lines(&dir.join("e"), "T", "x", "y", &[]).unwrap();
        assert!(empty.iter().all(|w| w.contains("font")));
        assert!(dir.join("e.png").is_file() && dir.join("e.svg").is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
