//! Error-against-time plots (plotters, log-log), each knob's Pareto front drawn as a line and the default circled.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

/// One series of a plot: named points (time s, error, label).
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64, String)>,
}

/// A plot of error against time.
pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    /// Pareto front over all series, as (time, error) in time order.
    pub front: Vec<(f64, f64)>,
    /// The default setting, circled and labelled.
    pub default: Option<(f64, f64)>,
}

const SIZE: (u32, u32) = (900, 560);
const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

/// Register the bundled font once (no system font libraries needed).
pub fn init_fonts() {
    static FONT: &[u8] = include_bytes!("DejaVuSans.ttf");
    let _ = register_font("sans-serif", FontStyle::Normal, FONT);
}

fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) =
        values.filter(|v| v.is_finite() && *v > 0.0).fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return 1e-3..1.0;
    }
    (lo / 2.0)..(hi * 2.0)
}

/// Render `plot` to PNG bytes.
pub fn render_png(plot: &Plot) -> Result<Vec<u8>, Box<dyn std::error::Error>> {
    let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let all = || plot.series.iter().flat_map(|s| s.points.iter());
        let x_range = log_range(all().map(|p| p.0));
        let y_range = log_range(all().map(|p| p.1));
        let mut chart = ChartBuilder::on(&root)
            .caption(&plot.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x_range.log_scale(), y_range.log_scale())?;
        chart
            .configure_mesh()
            .x_desc(&plot.x_label)
            .y_desc(&plot.y_label)
            .x_labels(8)
            .y_labels(10)
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style(("sans-serif", 14))
            .draw()?;
        if plot.front.len() > 1 {
            chart
                .draw_series(LineSeries::new(
                    plot.front.iter().cloned(),
                    ShapeStyle::from(&BLACK.mix(0.35)).stroke_width(6),
                ))?
                .label("Pareto front")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.mix(0.35).stroke_width(6)));
        }
        for (k, s) in plot.series.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let pts: Vec<(f64, f64)> = s.points.iter().filter(|p| p.0 > 0.0 && p.1 > 0.0).map(|p| (p.0, p.1)).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                .label(s.name.as_str())
                .legend(move |(x, y)| Circle::new((x + 9, y), 4, color.filled()));
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))?;
            chart.draw_series(s.points.iter().filter(|p| p.0 > 0.0 && p.1 > 0.0).map(|p| {
                EmptyElement::at((p.0, p.1))
                    + Text::new(p.2.clone(), (6, -14), ("sans-serif", 12).into_font().color(&color.mix(0.9)))
            }))?;
        }
        if let Some(d) = plot.default {
            chart
                .draw_series(std::iter::once(Circle::new(d, 11, RED.stroke_width(3))))?
                .label("default")
                .legend(|(x, y)| Circle::new((x + 9, y), 6, RED.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .draw()?;
        root.present()?;
    }
    let image = image::RgbImage::from_raw(SIZE.0, SIZE.1, rgb).ok_or("plot buffer size")?;
    let mut png = Vec::new();
    image::DynamicImage::ImageRgb8(image).write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)?;
    Ok(png)
}

/// Render `plot`, write it atomically to `path` and stamp it with the model's version.
pub fn write_plot(path: &Path, plot: &Plot) -> Result<(), Box<dyn std::error::Error>> {
    spectral_skin::maps::io::write_atomic(path, &render_png(plot)?)?;
    spectral_skin::stamp::stamp_png(path, super::markdown::REGENERATE)?;
    Ok(())
}
