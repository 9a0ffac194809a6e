//! Plots as PNG and SVG (plotters) of a [`Figure`]: error against the mesh size on log-log axes
//! ([`Figure::loglog`]), and curves on linear axes ([`Figure::lines`], e.g. force against
//! displacement).
//!
//! Text is drawn by plotters' pure-Rust `ab_glyph` renderer with a TrueType font read from disk
//! at run time (DejaVu Sans from Debian's `fonts-dejavu-core`, which `ci/setup` installs): no
//! fontconfig, no freetype, no network. When no font file is found the plot is still written,
//! without any text (no title, labels, tick values or legend), and the writers return a warning
//! saying so.
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
//! In [`Figure::lines`] and [`Figure::loglog_points`], a series' `flagged` points get a black
//! ring. Either axis is widened where needed so that the markers and rings of the outermost
//! points lie whole inside the plot area (`CLEARANCE` pixels from its edges).
//!
//! # Layout
//!
//! Nothing is drawn over the data: the figure (800 pixels wide) is the caption on top, the plot
//! area with the axes' labels left of and below it (800 x 600 pixels for these), and the
//! legend in a band of its own below the x axis's label, the figure growing by its height
//! (`Layout`, computed before anything is drawn, from the title, the legend entries and whether
//! there is text; the drawing places the plot area and the legend where it says). The legend's
//! entries fill as many columns as fit the figure's width (column by column, in series order),
//! in 18-pixel text, smaller (down to 12) for an entry too long for the width, and the figure
//! wider for one too long even then. In [`Figure::loglog`] the legend gives every series'
//! least-squares slope of log(error) against log(h) ([`fitted_slope`]), the observed order of
//! convergence; otherwise the series' names.

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
    /// Legend entry (in [`Figure::loglog`], the fitted slope is appended).
    pub name: String,
    /// `(x, y)` points, in drawing order: `(h, error)` in [`Figure::loglog`], where both must be
    /// positive and finite to appear; in [`Figure::lines`], both must be finite.
    pub points: Vec<(f64, f64)>,
    /// Points to flag with a black ring (load steps accepted without convergence, the Pareto
    /// front); [`Figure::lines`] and [`Figure::loglog_points`].
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

/// At most this many labelled ticks per axis.
const LABELS: usize = 10;

/// At most this many labelled ticks on a linear axis (its labels are longer: `-0.125`).
const LINEAR_LABELS: usize = 8;

/// A series of at most this many points has a marker on every point; a longer one on every k-th
/// point, about this many in all.
const MARKERS: usize = 30;

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

/// A figure to write: `<stem>.png` and `<stem>.svg`, with its title and axis labels.
#[derive(Clone, Copy, Debug)]
pub struct Figure<'a> {
    pub stem: &'a Path,
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
}

impl<'a> Figure<'a> {
    /// The figure at `stem` with this title and these axis labels.
    pub fn new(stem: &'a Path, title: &'a str, x_label: &'a str, y_label: &'a str) -> Self {
        Figure {
            stem,
            title,
            x_label,
            y_label,
        }
    }

    /// Writes the figure: log-log axes, one line with markers per series, a legend with each
    /// series' fitted slope, the title and the axis labels. Returns warnings (no font found:
    /// the plot has no text; points that cannot be shown on log axes).
    pub fn loglog(&self, series: &[Series]) -> Result<Vec<String>> {
        self.write::<LogAxis>(series, true)
    }

    /// Writes the figure: linear axes around the data (values of any sign), one line per series
    /// (with markers on at most about 30 of its points), a legend with the series' names, the
    /// title and the axis labels. Returns warnings (no font found: the plot has no text;
    /// non-finite points, which are not shown).
    pub fn lines(&self, series: &[Series]) -> Result<Vec<String>> {
        self.write::<LinearAxis>(series, false)
    }

    /// Writes the figure: points on log-log axes, one line per series in the given order, a
    /// legend with the series' names (no slopes), the `flagged` points ringed (e.g. the Pareto
    /// front of error against wall time). Returns warnings as [`Figure::loglog`].
    pub fn loglog_points(&self, series: &[Series]) -> Result<Vec<String>> {
        self.write::<LogAxis>(series, false)
    }

    /// The plot of `series` on axes of kind `A`; with `slopes`, the fitted slopes in the
    /// legend.
    fn write<A: Axis>(&self, series: &[Series], slopes: bool) -> Result<Vec<String>> {
        let mut warnings = font_warnings(self.stem);
        let texts = [self.title, self.x_label, self.y_label];
        let plot = Plot::<A>::new(texts, series, slopes, font().is_some(), &mut warnings);
        plot.write(self.stem)?;
        Ok(warnings)
    }
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

/// The figure's width, and its height without the legend band, in pixels.
const SIZE: (u32, u32) = (800, 600);

/// Space around the figure's content; on the right more (the last x tick label is centred on
/// the plot area's edge).
const MARGIN: i32 = 20;
const MARGIN_RIGHT: i32 = 30;

/// Width of the y axis's tick labels and description, left of the plot area.
const Y_LABEL_AREA: i32 = 85;

/// Height of the x axis's tick labels and description, below the plot area.
const X_LABEL_AREA: i32 = 60;

/// Space between the caption and the plot area (the top tick label is centred on its edge).
const CAPTION_GAP: i32 = 12;

/// Space between the x axis's label area and the legend.
const LEGEND_GAP: i32 = 8;

/// The legend's text size, and the smallest it is set at for an entry too long for the figure.
const LEGEND_FONT: f64 = 18.0;
const LEGEND_FONT_MIN: f64 = 12.0;

/// The legend's geometry: padding inside its frame, row height, the length of an entry's sample
/// line and the space after it, the space between columns.
const LEGEND_PAD: i32 = 12;
const LEGEND_ROW: i32 = 28;
const SWATCH: i32 = 36;
const SWATCH_GAP: i32 = 10;
const COLUMN_GAP: i32 = 24;

/// Radius of the ring around a flagged point (larger than any marker).
const RING: i32 = 10;

/// How far inside the plot area's edges a point is drawn at least: its ring (and stroke) whole.
const CLEARANCE: i32 = RING + 4;

/// A rectangle of pixels: `x0 <= x < x1`, `y0 <= y < y1` (y grows downwards).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Rect {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
}

impl Rect {
    fn width(&self) -> i32 {
        self.x1 - self.x0
    }

    fn height(&self) -> i32 {
        self.y1 - self.y0
    }
}

/// Where the parts of a figure go, in pixels: computed before anything is drawn
/// ([`Layout::new`]), and used by the drawing ([`Plot::draw`] draws the data inside `plot`,
/// the legend inside `legend.frame`).
#[derive(Clone, Debug, PartialEq)]
struct Layout {
    /// The figure's size.
    size: (u32, u32),
    /// The caption's font size and the top centre of its text (none without text).
    caption: Option<(f64, (i32, i32))>,
    /// The plot area: the data, its markers and rings are drawn inside it.
    plot: Rect,
    /// The plot area with the axes' label areas (left and below it, with text).
    chart: Rect,
    /// The legend (none without text or without series).
    legend: Option<LegendLayout>,
}

/// Where the legend goes: its frame, its text size, and per entry (in series order) the left
/// end of its sample line, at the middle of its row.
#[derive(Clone, Debug, PartialEq)]
struct LegendLayout {
    frame: Rect,
    font: f64,
    entries: Vec<(i32, i32)>,
}

impl Layout {
    /// The layout of a figure with this `title` and these legend `entries` (see the module
    /// docs); without `text`, the plot area fills the figure but for its margins.
    fn new(title: &str, entries: &[String], text: bool) -> Layout {
        let (width, height) = (SIZE.0 as i32, SIZE.1 as i32);
        if !text {
            let plot = Rect {
                x0: MARGIN,
                y0: MARGIN,
                x1: width - MARGIN_RIGHT,
                y1: height - MARGIN,
            };
            return Layout {
                size: SIZE,
                caption: None,
                plot,
                chart: plot,
                legend: None,
            };
        }
        let (font, cell) = legend_font(entries, width - 2 * MARGIN - 2 * LEGEND_PAD);
        let width = width.max(2 * MARGIN + 2 * LEGEND_PAD + cell);
        let caption = caption_size(width, title);
        let caption_band = 10 + (1.2 * caption).ceil() as i32;
        let plot = Rect {
            x0: MARGIN + Y_LABEL_AREA,
            y0: MARGIN + caption_band + CAPTION_GAP,
            x1: width - MARGIN_RIGHT,
            y1: height - MARGIN - X_LABEL_AREA,
        };
        let chart = Rect {
            x0: plot.x0 - Y_LABEL_AREA,
            y1: plot.y1 + X_LABEL_AREA,
            ..plot
        };
        let legend = (!entries.is_empty())
            .then(|| LegendLayout::new(entries.len(), (font, cell), width, chart.y1 + LEGEND_GAP));
        let height = legend.as_ref().map_or(height, |l| l.frame.y1 + MARGIN);
        Layout {
            size: (width as u32, height as u32),
            caption: Some((caption, (width / 2, MARGIN + 5))),
            plot,
            chart,
            legend,
        }
    }
}

impl LegendLayout {
    /// The legend of `n` entries whose cells (sample line and text at size `font`) are `cell`
    /// pixels wide, centred in a figure `width` wide, its top at `top`: as many columns as fit,
    /// filled column by column.
    fn new(n: usize, (font, cell): (f64, i32), width: i32, top: i32) -> LegendLayout {
        let room = width - 2 * MARGIN - 2 * LEGEND_PAD;
        let fit = usize::try_from((room + COLUMN_GAP) / (cell + COLUMN_GAP)).unwrap_or(1);
        let rows = n.div_ceil(fit.clamp(1, n));
        let columns = n.div_ceil(rows);
        let (rows_i, columns_i) = (rows as i32, columns as i32);
        let frame_width = 2 * LEGEND_PAD + columns_i * cell + (columns_i - 1) * COLUMN_GAP;
        let x0 = (width - frame_width) / 2;
        let frame = Rect {
            x0,
            y0: top,
            x1: x0 + frame_width,
            y1: top + 2 * LEGEND_PAD + rows_i * LEGEND_ROW - 8,
        };
        let entries = (0..n)
            .map(|i| {
                let (column, row) = ((i / rows) as i32, (i % rows) as i32);
                (
                    x0 + LEGEND_PAD + column * (cell + COLUMN_GAP),
                    top + LEGEND_PAD + LEGEND_ROW / 2 - 4 + row * LEGEND_ROW,
                )
            })
            .collect();
        LegendLayout {
            frame,
            font,
            entries,
        }
    }
}

/// The size in pixels of `text` in the plot font at `size`, as the backends measure it ((0, 0)
/// without a font).
fn text_size(text: &str, size: f64) -> (i32, i32) {
    (FAMILY, size)
        .into_font()
        .box_size(text)
        .map_or((0, 0), |(w, h)| (w as i32, h as i32))
}

/// The caption's font size: 28 pixels, or less (down to 12) so that a long title fits a figure
/// `width` pixels wide.
fn caption_size(width: i32, title: &str) -> f64 {
    let room = width - 60;
    let mut size = 28.0;
    while size > 12.0 && text_size(title, size).0 > room {
        size -= 1.0;
    }
    size
}

/// The legend's text size: [`LEGEND_FONT`], or less (down to [`LEGEND_FONT_MIN`]) so that the
/// widest of the `entries`, with its sample line, fits in `room` pixels; and the width of an
/// entry's cell (sample line and text) at that size.
fn legend_font(entries: &[String], room: i32) -> (f64, i32) {
    let cell = |size: f64| {
        let text = entries.iter().map(|e| text_size(e, size).0).max();
        SWATCH + SWATCH_GAP + text.unwrap_or(0)
    };
    let mut size = LEGEND_FONT;
    while size > LEGEND_FONT_MIN && cell(size) > room {
        size -= 1.0;
    }
    (size, cell(size))
}

/// What the plots need of an axis kind ([`LogAxis`], [`LinearAxis`]) beyond plotters' mapping.
trait Axis: Ranged<ValueType = f64, FormatOption = DefaultFormatting> + Clone + 'static {
    /// What a coordinate must be to be shown, for warnings ("finite").
    const SHOWN: &'static str;

    /// The margins of the x and y axes around the data ([`Axis::around`]'s `pad`).
    const PAD: [f64; 2];

    /// The ranges of the x and y axes of a plot without data.
    const EMPTY: [(f64, f64); 2];

    /// True if the coordinate `v` can be placed on this kind of axis.
    fn shows(v: f64) -> bool;

    /// The label of the tick at `v`.
    fn label(&self, v: f64) -> String;

    /// The axis around `values`, with a margin of `pad` (see the axis kind); `empty` without
    /// values.
    fn around(values: impl Iterator<Item = f64>, pad: f64, empty: (f64, f64)) -> Self;

    /// The axis over `[lo, hi]`.
    fn over(lo: f64, hi: f64) -> Self;

    /// The coordinate the axis is linear in (`v`, or `ln v`), and back.
    fn unit(v: f64) -> f64;
    fn from_unit(u: f64) -> f64;
}

/// `axis`, widened where needed so that every one of the `values` it shows lies at least
/// [`CLEARANCE`] pixels inside the ends of an axis `pixels` long: the markers and rings of the
/// outermost points are drawn whole, inside the plot area.
fn clear_of_edges<A: Axis>(axis: A, values: impl Iterator<Item = f64>, pixels: i32) -> A {
    let (lo, hi) = values
        .filter(|&v| A::shows(v))
        .map(A::unit)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), u| {
            (lo.min(u), hi.max(u))
        });
    if !(lo.is_finite() && hi.is_finite()) || pixels <= 2 * CLEARANCE {
        return axis;
    }
    let range = axis.range();
    let (below, above) = (lo - A::unit(range.start), A::unit(range.end) - hi);
    let q = f64::from(CLEARANCE) / f64::from(pixels);
    let data = hi - lo;
    // The shortest axis whose margins are both at least q of its length: its length is a fixed
    // point of `data + max(below, q L) + max(above, q L)`, the largest of those of its pieces.
    let length = [
        data + below + above,
        (data + below) / (1.0 - q),
        (data + above) / (1.0 - q),
        data / (1.0 - 2.0 * q),
    ]
    .into_iter()
    .fold(0.0, f64::max);
    let margin = q * length;
    if below >= margin && above >= margin {
        return axis;
    }
    // An end with room enough stays where it is.
    A::over(
        if below >= margin {
            range.start
        } else {
            A::from_unit(lo - margin)
        },
        if above >= margin {
            range.end
        } else {
            A::from_unit(hi + margin)
        },
    )
}

/// A plot ready to draw on any backend, on axes of kind `A`.
struct Plot<'a, A: Axis> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    /// Legend entries and the points that can be shown.
    curves: Vec<(String, Vec<(f64, f64)>)>,
    /// Points to ring (finite ones of every series' `flagged`).
    flagged: Vec<(f64, f64)>,
    x: A,
    y: A,
    text: bool,
    /// Where the parts go.
    layout: Layout,
}

impl<'a, A: Axis> Plot<'a, A> {
    /// The plot of `series` with its `[title, x label, y label]`: with `slopes`, the legend gives
    /// each series' fitted slope; without `text`, nothing is written on it.
    fn new(
        [title, x_label, y_label]: [&'a str; 3],
        series: &[Series],
        slopes: bool,
        text: bool,
        warnings: &mut Vec<String>,
    ) -> Plot<'a, A> {
        let curves: Vec<(String, Vec<(f64, f64)>)> = shown::<A>(title, series, warnings)
            .into_iter()
            .map(|(name, shown)| (legend_entry(name, &shown, slopes), shown))
            .collect();
        let flagged: Vec<(f64, f64)> = series
            .iter()
            .flat_map(|s| s.flagged.iter().copied())
            .filter(|&(x, y)| A::shows(x) && A::shows(y))
            .collect();
        let entries: Vec<String> = curves.iter().map(|c| c.0.clone()).collect();
        let layout = Layout::new(title, &entries, text);
        let all: Vec<(f64, f64)> = curves.iter().flat_map(|c| c.1.iter().copied()).collect();
        let marked = || all.iter().chain(&flagged);
        let x = A::around(all.iter().map(|p| p.0), A::PAD[0], A::EMPTY[0]);
        let x = clear_of_edges(x, marked().map(|p| p.0), layout.plot.width() - 1);
        let y = A::around(all.iter().map(|p| p.1), A::PAD[1], A::EMPTY[1]);
        let y = clear_of_edges(y, marked().map(|p| p.1), layout.plot.height() - 1);
        Plot {
            title,
            x_label,
            y_label,
            curves,
            flagged,
            x,
            y,
            text,
            layout,
        }
    }
}

/// The legend entry of a series with the `shown` points: its name, with its fitted slope when
/// `slopes` asks for it and there is one, or a note that it has no points.
fn legend_entry(name: &str, shown: &[(f64, f64)], slopes: bool) -> String {
    if shown.is_empty() {
        return format!("{name}: no points");
    }
    let slope = if slopes {
        fitted_slope(shown)
    } else {
        f64::NAN
    };
    if slope.is_finite() {
        format!("{name}: slope {slope:.2}")
    } else {
        name.to_string()
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

/// A chart of the plots, on axes of kind `A`.
type Chart<'c, DB, A> = ChartContext<'c, DB, Cartesian2d<A, A>>;

/// A drawing error of backend `DB`.
type DrawError<DB> = DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>;

impl<A: Axis> Plot<'_, A> {
    /// Writes `<stem>.png` and `<stem>.svg`, each atomically.
    fn write(&self, stem: &Path) -> Result<()> {
        let png = with_suffix(stem, "png");
        let svg = with_suffix(stem, "svg");
        let size = self.layout.size;

        let mut svg_text = String::new();
        {
            let root = SVGBackend::with_string(&mut svg_text, size).into_drawing_area();
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
                let root = BitMapBackend::new(&tmp, size).into_drawing_area();
                self.draw(&root)?;
            }
            std::fs::read(&tmp).map_err(|e| e.to_string())
        })();
        let _ = std::fs::remove_file(&tmp);
        let bytes = drawn
            .map_err(|e| Error::Other(format!("{}: cannot draw the plot: {e}", png.display())))?;
        write_atomic(&png, &bytes)
    }

    /// Draws the plot on `root` (a figure of the layout's size) and presents it; returns the
    /// plot area plotters drew the data in, which is the layout's (`layout.plot`).
    ///
    /// Markers and the legend are drawn in pixels on `root` with elements that do not carry the
    /// backend type: plotters' composed elements do, and its series and legend bounds then
    /// demand a `'static` backend, which one writing to a borrowed path or string is not.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<Rect, String> {
        let e = |e: DrawError<DB>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        if let Some((size, at)) = self.layout.caption {
            let style =
                TextStyle::from((FAMILY, size).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
            root.draw(&Text::new(self.title, at, style)).map_err(e)?;
        }
        let c = self.layout.chart;
        let area = root.clone().shrink((c.x0, c.y0), (c.width(), c.height()));
        let mut builder = ChartBuilder::on(&area);
        if self.text {
            builder
                .x_label_area_size(X_LABEL_AREA)
                .y_label_area_size(Y_LABEL_AREA);
        }
        let mut chart = builder
            .build_cartesian_2d(self.x.clone(), self.y.clone())
            .map_err(e)?;
        self.draw_axes(&mut chart).map_err(e)?;
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
        if let Some(legend) = &self.layout.legend {
            self.legend(root, legend).map_err(e)?;
        }
        root.present().map_err(e)?;
        let (x, y) = chart.plotting_area().get_pixel_range();
        Ok(Rect {
            x0: x.start,
            y0: y.start,
            x1: x.end,
            y1: y.end,
        })
    }

    /// The grid, the ticks and their labels, the axes' descriptions and the plot area's frame.
    fn draw_axes<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB, A>,
    ) -> std::result::Result<(), DrawError<DB>> {
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
        mesh.draw()?;

        // The frame (without text the axes above are not drawn).
        let (xr, yr) = (self.x.range(), self.y.range());
        chart.draw_series(std::iter::once(PathElement::new(
            vec![
                (xr.start, yr.start),
                (xr.end, yr.start),
                (xr.end, yr.end),
                (xr.start, yr.end),
                (xr.start, yr.start),
            ],
            BLACK.stroke_width(1),
        )))?;
        Ok(())
    }

    /// The legend where the layout puts it: per series a sample line with its marker, then its
    /// entry (name, slope), in a frame.
    fn legend<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        legend: &LegendLayout,
    ) -> std::result::Result<(), DrawError<DB>> {
        let style = TextStyle::from((FAMILY, legend.font).into_font())
            .pos(Pos::new(HPos::Left, VPos::Center));
        let f = legend.frame;
        let corners = [(f.x0, f.y0), (f.x1, f.y1)];
        root.draw(&Rectangle::new(corners, WHITE.mix(0.92).filled()))?;
        root.draw(&Rectangle::new(corners, RGBColor(120, 120, 120)))?;
        for (i, ((entry, _), &(x, y))) in self.curves.iter().zip(&legend.entries).enumerate() {
            let color = COLORS[i % COLORS.len()];
            root.draw(&PathElement::new(
                vec![(x, y), (x + SWATCH, y)],
                color.stroke_width(2),
            ))?;
            marker(root, i, (x + SWATCH / 2, y), color)?;
            root.draw(&Text::new(
                entry.clone(),
                (x + SWATCH + SWATCH_GAP, y),
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

/// A black ring around a flagged point at pixel `at` (larger than any series marker, and
/// unlike them not filled).
fn ring<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    at: (i32, i32),
) -> std::result::Result<(), DrawError<DB>> {
    root.draw(&Circle::new(at, RING, BLACK.stroke_width(2)))
}

/// Marker `shape` (circle, triangle, square, diamond, cross, by series) at pixel `at`.
fn marker<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    shape: usize,
    (x, y): (i32, i32),
    color: RGBColor,
) -> std::result::Result<(), DrawError<DB>> {
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
    const PAD: [f64; 2] = [0.08, 0.12];
    const EMPTY: [(f64, f64); 2] = [(0.1, 1.0), (0.01, 1.0)];

    fn shows(v: f64) -> bool {
        loggable(v)
    }

    fn label(&self, v: f64) -> String {
        tick_label(v)
    }

    fn around(values: impl Iterator<Item = f64>, pad: f64, empty: (f64, f64)) -> LogAxis {
        LogAxis::around(values, pad, empty)
    }

    fn over(lo: f64, hi: f64) -> LogAxis {
        LogAxis { lo, hi }
    }

    fn unit(v: f64) -> f64 {
        v.ln()
    }

    fn from_unit(u: f64) -> f64 {
        u.exp()
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
    const PAD: [f64; 2] = [0.04, 0.04];
    const EMPTY: [(f64, f64); 2] = [(0.0, 1.0), (0.0, 1.0)];

    fn shows(v: f64) -> bool {
        v.is_finite()
    }

    fn label(&self, v: f64) -> String {
        linear_label(v, self.tick_step(LINEAR_LABELS))
    }

    fn around(values: impl Iterator<Item = f64>, pad: f64, empty: (f64, f64)) -> LinearAxis {
        LinearAxis::around(values, pad, empty)
    }

    fn over(lo: f64, hi: f64) -> LinearAxis {
        LinearAxis { lo, hi }
    }

    fn unit(v: f64) -> f64 {
        v
    }

    fn from_unit(u: f64) -> f64 {
        u
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

    impl Rect {
        /// True if the two share a pixel.
        fn overlaps(&self, other: &Rect) -> bool {
            self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
        }

        /// True if `other` lies within this one.
        fn contains(&self, other: &Rect) -> bool {
            self.x0 <= other.x0 && other.x1 <= self.x1 && self.y0 <= other.y0 && other.y1 <= self.y1
        }
    }

    /// Checks a figure as it is drawn: the plot area plotters draws the data in is the
    /// layout's; the legend lies inside the figure, off the plot area and the axes' labels,
    /// and every entry's text inside its frame; every point (and ring) at least `CLEARANCE`
    /// pixels inside the plot area (1 pixel of rounding).
    fn check_figure<A: Axis>(name: &str, plot: &Plot<A>) {
        let layout = &plot.layout;
        let mut svg = String::new();
        let drawn = {
            let root = SVGBackend::with_string(&mut svg, layout.size).into_drawing_area();
            plot.draw(&root).unwrap()
        };
        assert_eq!(drawn, layout.plot, "{name}: the plot area drawn");
        let (w, h) = (layout.size.0 as i32, layout.size.1 as i32);
        let figure = Rect {
            x0: 0,
            y0: 0,
            x1: w,
            y1: h,
        };
        assert!(figure.contains(&layout.chart) && layout.chart.contains(&layout.plot));
        assert_eq!(
            layout.legend.is_some(),
            plot.text && !plot.curves.is_empty()
        );
        if let Some(legend) = &layout.legend {
            let frame = legend.frame;
            assert!(
                figure.contains(&frame),
                "{name}: legend {frame:?} in {figure:?}"
            );
            assert!(
                !frame.overlaps(&layout.plot),
                "{name}: legend over the data"
            );
            assert!(
                !frame.overlaps(&layout.chart),
                "{name}: legend over the axes"
            );
            assert_eq!(legend.entries.len(), plot.curves.len());
            for ((entry, _), &(x, y)) in plot.curves.iter().zip(&legend.entries) {
                let (tw, th) = text_size(entry, legend.font);
                let text = Rect {
                    x0: x,
                    y0: y - th / 2,
                    x1: x + SWATCH + SWATCH_GAP + tw,
                    y1: y + th / 2,
                };
                assert!(
                    frame.contains(&text),
                    "{name}: '{entry}' {text:?} in {frame:?}"
                );
            }
        }
        let p = layout.plot;
        let all = plot
            .curves
            .iter()
            .flat_map(|c| c.1.iter())
            .chain(&plot.flagged);
        for &(x, y) in all {
            let px = plot.x.map(&x, (p.x0, p.x1 - 1));
            let py = plot.y.map(&y, (p.y1 - 1, p.y0));
            let inside = Rect {
                x0: px - CLEARANCE + 1,
                y0: py - CLEARANCE + 1,
                x1: px + CLEARANCE,
                y1: py + CLEARANCE,
            };
            assert!(
                p.contains(&inside),
                "{name}: ({x}, {y}) at ({px}, {py}) in {p:?}"
            );
        }
    }

    /// `n` points of a variant's curve in the sliding blocks' study: pressed down at x = 0 up
    /// to about 52, then sliding to `end` with the force falling off; steps from `ringed` on
    /// ringed.
    fn sliding_curve(name: &str, scale: f64, end: f64, ringed: usize) -> Series {
        let mut points: Vec<(f64, f64)> = (0..=10).map(|i| (0.0, 5.2 * f64::from(i))).collect();
        let steps = (end / 0.0125).round() as i32;
        points.extend((1..=steps).map(|i| {
            let x = 0.0125 * f64::from(i);
            (x, scale * (52.0 - 40.0 * x * x - 1.0 * x))
        }));
        let flagged = points[ringed.min(points.len())..].to_vec();
        Series {
            name: name.into(),
            points,
            flagged,
        }
    }

    const SLIDING_BLOCKS: [&str; 6] = [
        "case1_hex27_twopass",
        "case2_hex27_lower_secondary",
        "case3_hex27_upper_secondary",
        "case4_hex8_lower_secondary",
        "case5_hex8_nts_twopass",
        "case6_hex8_nts_lower_secondary",
    ];

    /// Series of power laws over `xs`: `y = c x^p` per `(name, c, p)`.
    fn power_laws(xs: &[f64], laws: &[(&str, f64, f64)]) -> Vec<Series> {
        laws.iter()
            .map(|&(name, c, p)| Series {
                name: name.into(),
                points: xs.iter().map(|&x| (x, c * x.powf(p))).collect(),
                ..Default::default()
            })
            .collect()
    }

    /// The curves of cases/sliding_blocks/study.toml: its 6 cases, the node-on-segment
    /// baselines stopped early with unconverged steps ringed.
    fn check_sliding_blocks_curves(text: bool) {
        let mut curves: Vec<Series> = SLIDING_BLOCKS[..4]
            .iter()
            .enumerate()
            .map(|(i, name)| sliding_curve(name, 1.0 + 0.003 * i as f64, 0.5, usize::MAX))
            .collect();
        curves.push(sliding_curve(SLIDING_BLOCKS[4], 1.0, 0.15, 18));
        curves.push(sliding_curve(SLIDING_BLOCKS[5], 0.98, 0.15, 5));
        for s in &mut curves[4..] {
            let stopped = s.points.last().unwrap().0;
            let ringed = s.flagged.len();
            s.name = format!(
                "{}: {ringed} unconverged steps (ringed), stopped at {stopped:.3}",
                s.name
            );
        }
        let title = "Sliding blocks: vertical force against horizontal displacement";
        let texts = [
            title,
            "horizontal displacement of the top",
            "vertical force",
        ];
        let mut w = Vec::new();
        let plot = Plot::<LinearAxis>::new(texts, &curves, false, text, &mut w);
        check_figure("sliding_blocks curves", &plot);
        assert!(w.is_empty(), "{w:?}");
    }

    /// The Pareto plot of cases/sliding_blocks/study.toml: 6 variants, of which cases 2 to 4
    /// have a point, two of them on the front.
    fn check_sliding_blocks_pareto(text: bool) {
        let points = [(6.54, 1.57e-3), (4.97, 3.49e-3), (5.81, 1.26e-2)];
        let series: Vec<Series> = SLIDING_BLOCKS
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let mine: Vec<(f64, f64)> =
                    points.get(i.wrapping_sub(1)).copied().into_iter().collect();
                Series {
                    name: name.to_string(),
                    flagged: mine.iter().copied().filter(|p| p.1 < 4e-3).collect(),
                    points: mine,
                }
            })
            .collect();
        let metric = "curve_max_rel_diff to case1_hex27_twopass";
        let title =
            format!("sliding_blocks_study: {metric} against wall time (ringed: Pareto front)");
        let texts = [title.as_str(), "wall time (s)", metric];
        let mut w = Vec::new();
        let plot = Plot::<LogAxis>::new(texts, &series, false, text, &mut w);
        check_figure("sliding_blocks pareto", &plot);
        assert!(w.is_empty(), "{w:?}");
    }

    /// Convergence plots: cases/thick_sphere (3 variants), cases/contact_patch (6, a metric
    /// list), cases/thick_sphere_tied (5, the longest names); and `mortar scaling` on 1 and 2
    /// ranks (the total, the ideal and 4 phases).
    fn check_convergence_and_scaling(text: bool) {
        let hs = [0.5, 1.0 / 3.0, 0.25];
        let sphere = [
            ("hex8", 0.7, 0.9),
            ("hex20", 0.24, 1.8),
            ("hex27", 0.24, 1.8),
        ];
        let patch = [
            "hex8_scheme2",
            "hex8_scheme3",
            "hex8_twopass",
            "hex27_scheme2",
            "node_on_segment",
            "hex8_scheme2_fan",
        ]
        .map(|name| (name, 1e-13, 0.5));
        let tied = [
            ("scheme2_onepass_fine_secondary", 0.3, 1.9),
            ("scheme2_onepass_coarse_secondary", 0.32, 1.85),
            ("scheme2_twopass", 0.29, 1.9),
            ("conforming", 0.28, 2.0),
            ("scheme2_onepass_fan", 0.3, 1.9),
        ];
        let p = -(1.7f64.log2());
        let scaling = [
            ("total (wall)", 10.0, p),
            ("ideal", 10.0, -1.0),
            ("linear solve", 4.0, p),
            ("mortar integration", 3.0, p),
            ("contact assembly", 1.0, p),
            ("bulk assembly", 0.5, p),
        ];
        let h = "mesh size h";
        let patch_metric = "max(max_rel_stress_error, max_rel_penetration_blocks)";
        let figures = [
            (
                "Thick sphere: energy-norm error",
                h,
                "energy_error",
                &hs[..],
                &sphere[..],
                true,
            ),
            (
                "Contact patch test: stress error and penetration",
                h,
                patch_metric,
                &[1.0 / 3.0, 1.0 / 6.0][..],
                &patch[..],
                true,
            ),
            (
                "Thick sphere, tied dissimilar interface (Hex20)",
                h,
                "energy_error",
                &hs[..],
                &tied[..],
                true,
            ),
            (
                "Strong scaling: speedup 1.70 on 2 ranks",
                "ranks",
                "wall time (s)",
                &[1.0, 2.0][..],
                &scaling[..],
                false,
            ),
        ];
        for (title, x_label, y_label, xs, laws, slopes) in figures {
            let mut w = Vec::new();
            let series = power_laws(xs, laws);
            let texts = [title, x_label, y_label];
            check_figure(
                title,
                &Plot::<LogAxis>::new(texts, &series, slopes, text, &mut w),
            );
            assert!(w.is_empty(), "{w:?}");
        }
    }

    /// The figures the shipped studies draw, with their numbers of series and their longest
    /// legend entries (cases/*/study*.toml, `mortar scaling`): the legend is never over the data
    /// and every point is drawn whole inside the plot area.
    #[test]
    fn shipped_figures_keep_the_legend_off_the_data() {
        let text = font().is_some();
        check_sliding_blocks_curves(text);
        check_sliding_blocks_pareto(text);
        check_convergence_and_scaling(text);
    }

    /// The legend takes as many columns as fit, below the axes, and the figure grows by its
    /// band; an entry too long for the width is set smaller, and one too long even then widens
    /// the figure. Without text or series there is no legend.
    #[test]
    fn legend_fills_columns_and_grows_the_figure() {
        let bare = Layout::new("T", &["a".to_string()], false);
        assert_eq!((bare.size, bare.legend.is_none()), (SIZE, true));
        assert_eq!(bare.plot, bare.chart);
        if font().is_none() {
            return; // no font on this machine: plots have no text
        }
        let none = Layout::new("T", &[], true);
        assert_eq!((none.size, none.legend.is_none()), (SIZE, true));
        let short: Vec<String> = ["hex8", "hex20", "hex27"].map(String::from).to_vec();
        let l = Layout::new("T", &short, true);
        let legend = l.legend.as_ref().unwrap();
        assert_eq!(legend.font, LEGEND_FONT);
        // One row of three columns, below the x axis's labels.
        assert!(legend.entries.iter().all(|e| e.1 == legend.entries[0].1));
        assert!(
            legend.entries[0].0 < legend.entries[1].0 && legend.entries[1].0 < legend.entries[2].0
        );
        assert_eq!(legend.frame.y0, l.chart.y1 + LEGEND_GAP);
        assert_eq!(l.size, (SIZE.0, (legend.frame.y1 + MARGIN) as u32));
        // Six long names: two columns of three rows, filled column by column.
        let long: Vec<String> = SLIDING_BLOCKS.map(String::from).to_vec();
        let legend = Layout::new("T", &long, true).legend.unwrap();
        let e = &legend.entries;
        assert!(
            e[0].0 == e[2].0 && e[3].0 == e[5].0 && e[0].0 < e[3].0,
            "{e:?}"
        );
        assert!(
            e[0].1 < e[1].1 && e[1].1 < e[2].1 && e[0].1 == e[3].1,
            "{e:?}"
        );
        // Too long for 18 pixels: smaller; too long even at 12: a wider figure.
        let longer = vec![format!(
            "{}: 15 unconverged steps (ringed), stopped at 0.150 of 0.5",
            long[5]
        )];
        let l = Layout::new("T", &longer, true);
        assert!(l.legend.unwrap().font < LEGEND_FONT);
        let longest = vec![longer[0].repeat(2)];
        let l = Layout::new("T", &longest, true);
        assert_eq!(l.legend.as_ref().unwrap().font, LEGEND_FONT_MIN);
        assert!(
            l.size.0 > SIZE.0 && l.plot.x1 == l.size.0 as i32 - MARGIN_RIGHT,
            "{l:?}"
        );
    }

    /// An axis whose outermost points would be drawn less than `CLEARANCE` pixels from its ends
    /// is widened just enough; one with room is left as it is.
    #[test]
    fn outermost_points_clear_the_plot_edges() {
        let pixels = 400;
        let tight = LinearAxis { lo: 0.0, hi: 1.0 };
        let a = clear_of_edges(tight, [0.0, 0.5, 1.0].into_iter(), pixels);
        let (lo, hi) = (a.map(&0.0, (0, pixels)), a.map(&1.0, (0, pixels)));
        assert!(
            lo == CLEARANCE && hi == pixels - CLEARANCE,
            "{a:?}: {lo}, {hi}"
        );
        let roomy = LinearAxis { lo: -1.0, hi: 2.0 };
        let a = clear_of_edges(roomy, [0.0, 1.0].into_iter(), pixels);
        assert_eq!((a.lo, a.hi), (-1.0, 2.0));
        // One end only, on a log axis: the other keeps its margin.
        let log = LogAxis { lo: 0.01, hi: 10.0 };
        let a = clear_of_edges(log, [0.01, 1.0].into_iter(), pixels);
        assert!(
            a.map(&0.01, (0, pixels)) >= CLEARANCE && a.hi == 10.0,
            "{a:?}"
        );
        // Nothing to show: as it was.
        let a = clear_of_edges(
            LogAxis { lo: 0.1, hi: 1.0 },
            [f64::NAN, -1.0].into_iter(),
            pixels,
        );
        assert_eq!((a.lo, a.hi), (0.1, 1.0));
    }

    /// A short title keeps the 28-pixel caption; a long one (a study's Pareto title) is set
    /// smaller, so that it fits the width of the plot.
    #[test]
    fn a_long_caption_is_set_smaller_to_fit() {
        if font().is_none() {
            return; // no font on this machine: plots have no text
        }
        let mut svg = String::new();
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        let width = SIZE.0 as i32;
        assert_eq!(caption_size(width, "Hertz"), 28.0);
        let long = "study_solver: curve_max_rel_diff to reference against wall time (ringed: \
                    Pareto front)";
        let size = caption_size(width, long);
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
        let warnings = Figure::new(&stem, "Title", "h", "error")
            .loglog(&sample())
            .unwrap();
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
        let plot = Plot::<LogAxis>::new(["T", "h", "e"], &sample(), true, false, &mut warnings);
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
        let w = Figure::new(&dir.join("c"), "T", "h", "e")
            .loglog(&s)
            .unwrap();
        assert!(w.iter().any(|w| w.contains("2 point(s) of 'x'")), "{w:?}");
        let empty = Figure::new(&dir.join("d"), "T", "h", "e")
            .loglog(&[])
            .unwrap();
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
        Figure::new(&dir.join("m"), "T", "x", "y")
            .lines(&s)
            .unwrap();
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
        let warnings = Figure::new(&stem, "Reaction", "u_z", "reaction")
            .lines(&series)
            .unwrap();
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
        let w = Figure::new(&dir.join("c"), "T", "x", "y")
            .lines(&s)
            .unwrap();
        let dropped: Vec<&String> = w.iter().filter(|w| w.contains("point(s)")).collect();
        assert_eq!(dropped.len(), 1, "{w:?}");
        assert!(
            dropped[0].contains("2 point(s) of 'x' are not finite"),
            "{w:?}"
        );
        let mut warnings = Vec::new();
        let plot = Plot::<LinearAxis>::new(["T", "x", "y"], &s, false, false, &mut warnings);
        assert_eq!(plot.curves[0].1, vec![(0.0, 1.0), (-1.0, -3.0)]);
        assert_eq!(plot.curves[1].1, s[1].points);
        assert!(plot.x.lo < -2.0 && plot.x.hi > 0.0 && plot.y.lo < -5.0 && plot.y.hi > 1.0);
        plot.write(&dir.join("d")).unwrap();
        let svg = std::fs::read_to_string(dir.join("d.svg")).unwrap();
        assert!(!svg.contains("<text"));
        let empty = Figure::new(&dir.join("e"), "T", "x", "y")
            .lines(&[])
            .unwrap();
        assert!(empty.iter().all(|w| w.contains("font")));
        assert!(dir.join("e.png").is_file() && dir.join("e.svg").is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
