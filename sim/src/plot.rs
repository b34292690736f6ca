//! SVG charts for the report, drawn with `plotters`' SVG backend (no system fonts: text is
//! written as SVG `<text>` and laid out with plotters' built-in size estimate). Each function
//! returns the SVG document as a string; the output depends only on the data.

use plotters::prelude::*;

/// Series colours.
const PALETTE: [RGBColor; 9] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x7f, 0x7f, 0x7f),
    RGBColor(0xbc, 0xbd, 0x22),
];

/// The colour of series `i`.
pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

type R = Result<String, String>;

fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("plot: {e:?}")
}

fn nice_max(v: f64) -> f64 {
    if v.is_nan() || v <= 0.0 || !v.is_finite() {
        return 1.0;
    }
    let p = 10f64.powf(v.log10().floor());
    for m in [1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0] {
        if m * p >= v * 1.05 {
            return m * p;
        }
    }
    10.0 * p
}

/// A horizontal reference line with a label.
#[derive(Clone, Debug)]
pub struct HLine {
    /// Value.
    pub y: f64,
    /// Label.
    pub label: String,
}

/// A chart with `f64` axes on the SVG backend.
type Chart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// Draws `h` across the chart from 0 to `x_end`, with its legend entry.
fn reference_line(chart: &mut Chart<'_, '_>, h: HLine, x_end: f64) -> Result<(), String> {
    chart
        .draw_series(LineSeries::new(vec![(0.0, h.y), (x_end, h.y)], BLACK.stroke_width(1)))
        .map_err(err)?
        .label(h.label)
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], BLACK));
    Ok(())
}

/// Draws the legend at `position` (in the default font, or at `font_size` points).
fn legend<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    position: SeriesLabelPosition,
    font_size: Option<u32>,
) -> Result<(), String> {
    let mut labels = chart.configure_series_labels();
    labels.position(position).background_style(WHITE.mix(0.85)).border_style(BLACK);
    if let Some(size) = font_size {
        labels.label_font(("sans-serif", size));
    }
    labels.draw().map_err(err)
}

/// The axes of an x-y chart over `x` and `y`, drawn with its caption, mesh and axis titles.
fn xy_chart<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    title: &str,
    (x_desc, y_desc): (&str, &str),
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
) -> Result<Chart<'a, 'b>, String> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64)
        .build_cartesian_2d(x, y)
        .map_err(err)?;
    chart
        .configure_mesh()
        .light_line_style(WHITE)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 15))
        .x_desc(x_desc)
        .y_desc(y_desc)
        .draw()
        .map_err(err)?;
    Ok(chart)
}

/// Grouped bars: one group per entry of `groups`, one bar per series in each.
pub fn grouped_bars(
    title: &str,
    y_desc: &str,
    groups: &[String],
    series: &[(String, Vec<f64>)],
    hline: Option<HLine>,
) -> R {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (820, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let ymax = series
            .iter()
            .flat_map(|s| s.1.iter().copied())
            .chain(hline.iter().map(|h| h.y))
            .fold(0.0, f64::max);
        let ymax = nice_max(ymax * 1.3);
        let ng = groups.len().max(1) as f64;
        let mut chart = category_chart(&root, title, y_desc, groups, ng, ymax, groups.len().max(1) * 2 + 1)?;
        let ns = series.len().max(1) as f64;
        let width = 0.8 / ns;
        for (si, (name, vals)) in series.iter().enumerate() {
            let c = color(si);
            chart
                .draw_series(vals.iter().enumerate().map(|(gi, &v)| {
                    let x0 = gi as f64 + 0.1 + si as f64 * width;
                    Rectangle::new([(x0, 0.0), (x0 + width * 0.92, v.max(0.0))], c.filled())
                }))
                .map_err(err)?
                .label(name.clone())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
        }
        if let Some(h) = hline {
            reference_line(&mut chart, h, ng)?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight, Some(14))?;
        root.present().map_err(err)?;
    }
    Ok(out)
}

/// The axes of a bar chart whose category `i` (named `names[i]`) spans `[i, i + 1)` on an x axis
/// from 0 to `x_max` with `x_labels` label positions, and values from 0 to `ymax`; drawn with
/// its caption and mesh.
fn category_chart<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    title: &str,
    y_desc: &str,
    names: &[String],
    x_max: f64,
    ymax: f64,
    x_labels: usize,
) -> Result<Chart<'a, 'b>, String> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(64)
        .build_cartesian_2d(0f64..x_max, 0f64..ymax)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .light_line_style(WHITE)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 15))
        .x_labels(x_labels)
        .x_label_formatter(&|x| category_label(names, *x))
        .y_desc(y_desc)
        .draw()
        .map_err(err)?;
    Ok(chart)
}

/// The label of category `i` on a bar chart whose category `i` spans `[i, i + 1)` on the x axis:
/// the name at the middle of the span, nothing elsewhere.
fn category_label(names: &[String], x: f64) -> String {
    let i = x.floor() as usize;
    if (x - x.floor() - 0.5).abs() < 0.26 && i < names.len() {
        names[i].clone()
    } else {
        String::new()
    }
}

/// Stacked bars: one bar per entry of `bars`; each stack series gives one value per bar.
pub fn stacked_bars(title: &str, y_desc: &str, bars: &[String], stacks: &[(String, Vec<f64>)]) -> R {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (820, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let totals: Vec<f64> = (0..bars.len())
            .map(|b| stacks.iter().map(|s| s.1.get(b).copied().unwrap_or(0.0)).sum())
            .collect();
        let ymax = nice_max(totals.iter().copied().fold(0.0, f64::max));
        let nb = bars.len().max(1) as f64;
        let mut chart =
            category_chart(&root, title, y_desc, bars, nb + 1.6, ymax, bars.len().max(1) * 2 + 4)?;
        let mut base = vec![0.0; bars.len()];
        for (si, (name, vals)) in stacks.iter().enumerate() {
            let c = color(si);
            let rects: Vec<_> = (0..bars.len())
                .map(|b| {
                    let v = vals.get(b).copied().unwrap_or(0.0).max(0.0);
                    let r = Rectangle::new(
                        [(b as f64 + 0.15, base[b]), (b as f64 + 0.85, base[b] + v)],
                        c.filled(),
                    );
                    base[b] += v;
                    r
                })
                .collect();
            chart
                .draw_series(rects)
                .map_err(err)?
                .label(name.clone())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight, None)?;
        root.present().map_err(err)?;
    }
    Ok(out)
}

/// Line chart of `(x, y)` series.
pub fn lines(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
    hline: Option<HLine>,
) -> R {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (820, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let pts = || series.iter().flat_map(|s| s.1.iter().copied());
        let xmax = pts().map(|p| p.0).fold(0.0, f64::max).max(1.0);
        let ymax = nice_max(pts().map(|p| p.1).chain(hline.iter().map(|h| h.y)).fold(0.0, f64::max));
        let mut chart = xy_chart(&root, title, (x_desc, y_desc), 0f64..xmax, 0f64..ymax)?;
        for (si, (name, p)) in series.iter().enumerate() {
            let c = color(si);
            chart
                .draw_series(LineSeries::new(p.iter().copied(), c.stroke_width(2)))
                .map_err(err)?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], c.stroke_width(2)));
            chart.draw_series(p.iter().map(|&q| Circle::new(q, 2, c.filled()))).map_err(err)?;
        }
        if let Some(h) = hline {
            reference_line(&mut chart, h, xmax)?;
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight, None)?;
        root.present().map_err(err)?;
    }
    Ok(out)
}

/// Scatter of point groups with a front drawn as a line (e.g. the Pareto front).
pub fn scatter_front(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    groups: &[(String, Vec<(f64, f64)>)],
    front: &[(f64, f64)],
) -> R {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (820, 500)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let pts = || groups.iter().flat_map(|g| g.1.iter().copied());
        let (xlo, xhi) =
            (pts().map(|p| p.0).fold(f64::INFINITY, f64::min), pts().map(|p| p.0).fold(0.0, f64::max));
        let pad = ((xhi - xlo) * 0.08).max(xhi * 0.02).max(1e-9);
        let (xmin, xmax) = if xlo.is_finite() { ((xlo - pad).max(0.0), xhi + pad) } else { (0.0, 1.0) };
        let ymin = pts().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let ymax = pts().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        let (ymin, ymax) =
            if ymin.is_finite() { ((ymin - 2.0).floor(), (ymax + 2.0).ceil()) } else { (0.0, 1.0) };
        let mut chart = xy_chart(&root, title, (x_desc, y_desc), xmin..xmax, ymin..ymax)?;
        if front.len() > 1 {
            chart
                .draw_series(LineSeries::new(front.iter().copied(), BLACK.stroke_width(1)))
                .map_err(err)?
                .label("Pareto front")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], BLACK));
        }
        for (gi, (name, p)) in groups.iter().enumerate() {
            let c = color(gi);
            chart
                .draw_series(p.iter().map(|&q| Circle::new(q, 4, c.filled())))
                .map_err(err)?
                .label(name.clone())
                .legend(move |(x, y)| Circle::new((x + 6, y), 4, c.filled()));
        }
        legend(&mut chart, SeriesLabelPosition::LowerLeft, None)?;
        root.present().map_err(err)?;
    }
    Ok(out)
}

/// The Pareto front of points where larger `x` and larger `y` are better, sorted by `x`.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> =
        points.iter().copied().filter(|q| q.0.is_finite() && q.1.is_finite()).collect();
    // By x descending; keep a point when its y beats every point with a larger x.
    p.sort_by(|a, b| b.0.total_cmp(&a.0).then(b.1.total_cmp(&a.1)));
    let mut front = Vec::new();
    let mut best = f64::NEG_INFINITY;
    for q in p {
        if q.1 > best {
            front.push(q);
            best = q.1;
        }
    }
    front.reverse();
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let pts = [(1.0, 5.0), (2.0, 4.0), (2.0, 3.0), (3.0, 1.0), (0.5, 4.5), (1.5, 5.5)];
        let f = pareto_front(&pts);
        assert_eq!(f, vec![(1.5, 5.5), (2.0, 4.0), (3.0, 1.0)]);
        for p in pts {
            let dominated = pts.iter().any(|q| q.0 >= p.0 && q.1 >= p.1 && q != &p);
            assert_eq!(!f.contains(&p), dominated || p == (2.0, 3.0), "{p:?}");
        }
    }

    #[test]
    fn charts_are_svg_with_their_labels_and_deterministic() {
        let s = grouped_bars(
            "FPS",
            "frames/s",
            &["HD".into(), "QHD".into()],
            &[("neo".into(), vec![100.0, 50.0]), ("gscore".into(), vec![60.0, 20.0])],
            Some(HLine { y: 60.0, label: "60 FPS".into() }),
        )
        .unwrap();
        assert!(s.starts_with("<svg") && s.contains("QHD") && s.contains("gscore") && s.contains("60 FPS"));
        let s2 = grouped_bars(
            "FPS",
            "frames/s",
            &["HD".into(), "QHD".into()],
            &[("neo".into(), vec![100.0, 50.0]), ("gscore".into(), vec![60.0, 20.0])],
            Some(HLine { y: 60.0, label: "60 FPS".into() }),
        )
        .unwrap();
        assert_eq!(s, s2);
        let st = stacked_bars(
            "DRAM",
            "GB",
            &["neo".into()],
            &[("sort".into(), vec![1.0]), ("raster".into(), vec![2.0])],
        )
        .unwrap();
        assert!(st.contains("raster"));
        let l = lines("t", "frame", "ms", &[("neo".into(), vec![(0.0, 1.0), (1.0, 2.0)])], None).unwrap();
        assert!(l.contains("neo"));
        let sc = scatter_front(
            "s",
            "FPS",
            "dB",
            &[("neo".into(), vec![(1.0, 40.0), (2.0, 30.0)])],
            &[(1.0, 40.0), (2.0, 30.0)],
        )
        .unwrap();
        assert!(sc.contains("Pareto"));
    }
}
