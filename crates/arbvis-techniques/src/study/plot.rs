//! The studies' one plot: error against time on log-log axes, a line and dots per
//! series, and optional vertical lines (a time without an error: a setting that draws
//! another picture, such as the unclipped volume). Every study draws through
//! [`plot_lines`].

use std::path::Path;

use arbvis_core::image::Image;
use arbvis_core::vocab::TargetFormat;

/// Titles of a plot.
#[derive(Debug, Clone, Copy)]
pub struct Chart<'a> {
    /// Above the plot.
    pub title: &'a str,
    /// The x axis (a time), without "(log)".
    pub x: &'a str,
    /// The y axis (an error), without "(log)".
    pub y: &'a str,
}

/// Named series of (x, y) points.
pub type Lines = [(String, Vec<(f64, f64)>)];

/// Plot `lines` on log axes into a 1100x700 PNG at `path`, with a vertical line at each
/// `verticals` x and its label. Points whose x or y is not finite or negative are left
/// out (not measured); an error of exactly 0 cannot sit on a log axis, so it is drawn on
/// the bottom edge and the y axis says so. Fails when no point is left.
pub fn plot_lines(
    lines: &Lines,
    path: &Path,
    chart: &Chart,
    verticals: &[(f64, String)],
) -> anyhow::Result<()> {
    use plotters::prelude::*;
    register_plot_font()?;
    let kept = |&(x, y): &(f64, f64)| x.is_finite() && x > 0.0 && y.is_finite() && y >= 0.0;
    let points: Vec<(f64, f64)> = lines
        .iter()
        .flat_map(|(_, p)| p.iter().copied())
        .filter(kept)
        .collect();
    if points.is_empty() {
        anyhow::bail!("nothing to plot: no setting has both a time and an error");
    }
    let verticals: Vec<&(f64, String)> = verticals
        .iter()
        .filter(|v| v.0.is_finite() && v.0 > 0.0)
        .collect();
    let xs = points
        .iter()
        .map(|p| p.0)
        .chain(verticals.iter().map(|v| v.0));
    let (x0, x1) = range(xs);
    let (y0, y1) = range(points.iter().map(|p| p.1).filter(|&y| y > 0.0));
    let has_zero = points.iter().any(|p| p.1 == 0.0);
    // No positive error at all: a decade below 1e-6 holds the zeros.
    let (y0, y1) = if y0.is_finite() {
        (y0, y1)
    } else {
        (1e-7, 1e-6)
    };
    let (x0, x1, y0, y1) = (x0 * 0.8, x1 * 1.25, y0 * 0.5, y1 * 1.25);
    // The legend sits at the upper right: stretch the x axis so that the points keep to
    // the left of it (about 7 pixels a character of the longest label, plus the sample
    // line, of about 1000 pixels of plot).
    let longest = lines
        .iter()
        .map(|l| l.0.chars().count())
        .chain(verticals.iter().map(|v| v.1.chars().count()))
        .max()
        .unwrap_or(0);
    let share = (1.0 - (longest as f64 * 7.0 + 60.0) / 1000.0).clamp(0.5, 0.9);
    let x1 = x0 * (x1 / x0).powf(1.0 / share);
    let y_desc = if has_zero {
        format!("{} (log; 0 on the bottom edge)", chart.y)
    } else {
        format!("{} (log)", chart.y)
    };
    let (w, h) = (1100u32, 700u32);
    let mut buffer = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut plot = ChartBuilder::on(&root)
            .caption(chart.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        plot.configure_mesh()
            .x_desc(format!("{} (log)", chart.x))
            .y_desc(y_desc)
            .label_style(("sans-serif", 14))
            .draw()?;
        for (n, (name, pts)) in lines.iter().enumerate() {
            let colour = Palette99::pick(n).to_rgba();
            let mut pts: Vec<(f64, f64)> = pts
                .iter()
                .filter(|p| kept(p))
                .map(|&(x, y)| (x, if y > 0.0 { y } else { y0 }))
                .collect();
            if pts.is_empty() {
                continue;
            }
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            plot.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            plot.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
        }
        for (x, label) in verticals {
            plot.draw_series(LineSeries::new(
                vec![(*x, y0), (*x, y1)],
                BLACK.stroke_width(1),
            ))?
            .label(label.as_str())
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
        }
        plot.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
        root.present()?;
    }
    save_plot(&buffer, w, h, path)
}

/// Smallest and largest of `values` (infinite, 0 when there are none).
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// The plots' font: the annotations' ([`crate::annotate::register_font`]).
fn register_plot_font() -> anyhow::Result<()> {
    crate::annotate::register_font().map_err(anyhow::Error::msg)
}

/// Write a plotters RGB buffer as an opaque PNG (atomically).
fn save_plot(buffer: &[u8], w: u32, h: u32, path: &Path) -> anyhow::Result<()> {
    let data: Vec<f32> = buffer
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255].map(|v| v as f32 / 255.0))
        .collect();
    let image = Image {
        width: w,
        height: h,
        format: TargetFormat::Rgba8,
        data,
    };
    arbvis_core::png_io::write_png(path, &image, &[("Software", "arbvis study".into())])?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart() -> Chart<'static> {
        Chart {
            title: "t",
            x: "ms",
            y: "RMSE",
        }
    }

    #[test]
    fn draws_points_zeros_and_verticals_and_refuses_an_empty_plot() {
        let dir = std::env::temp_dir().join(format!("arbvis-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("p.png");
        let lines = vec![
            (
                "a".to_string(),
                vec![(3.0, 0.02), (17.0, 0.004), (90.0, 0.0)],
            ),
            // Unmeasured errors (NaN) are left out, not drawn.
            ("b".to_string(), vec![(5.0, f64::NAN)]),
        ];
        plot_lines(&lines, &png, &chart(), &[(41.0, "no clip".into())]).unwrap();
        let (image, _) = arbvis_core::png_io::read_png(&png).unwrap();
        assert_eq!((image.width, image.height), (1100, 700));
        // The first series is drawn in the palette's first colour: its line (three
        // segments, each tens of pixels long) and the legend's sample, well over 100
        // pixels; "b" has no point to draw.
        use plotters::style::{Color, Palette, Palette99};
        let c = Palette99::pick(0).to_rgba();
        let colour = [c.0, c.1, c.2].map(|v| v as f32 / 255.0);
        let drawn = image
            .data
            .chunks_exact(4)
            .filter(|p| p[..3] == colour)
            .count();
        assert!(drawn > 100, "{drawn}");
        let nothing = vec![("b".to_string(), vec![(5.0, f64::NAN), (f64::NAN, 1.0)])];
        let e = plot_lines(&nothing, &dir.join("q.png"), &chart(), &[]).unwrap_err();
        assert!(e.to_string().contains("nothing to plot"), "{e}");
        assert!(!dir.join("q.png").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
