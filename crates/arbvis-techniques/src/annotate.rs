//! Legends and axes drawn into an offscreen picture, as ParaView users put them in a figure
//! for a report: each colour table as a bar with its value range, isovalues and classes as
//! keys, and the box's three axes with ticks in the data's own numbers (inline, crossline
//! and time for a survey; x, y, z for a cloud). A scene's `legend = true` and `axes = true`
//! (or `render --legend --axes`) ask for them.
//!
//! Decisions:
//! - **Off unless asked**, in both fidelities: a faithful picture is compared with the
//!   original programs, a precise one with the f64 reference, and both must hold the
//!   renderer's pixels alone.
//! - Drawn with plotters' bitmap backend in egui's Ubuntu font (both already in the build)
//!   over an 8-bit copy of the picture; only the pixels the overlay changes are written
//!   back (opaque), so the rest keeps a float target's precision.
//! - Legends stack in the top right corner, text in white on dark backgrounds and black on
//!   light ones (read from the picture's corner), over a panel of that background at 75 %
//!   (a white section or a bright surface behind a legend would hide its white numbers). Each axis is drawn along the box edge
//!   parallel to it that lies farthest out on screen, its labels outside the box; an axis
//!   seen nearly end on (shorter than four text heights) is left out.

use crate::error::AnnotateError;
use glam::{DVec2, DVec3, DVec4};

use crate::techniques::annotations::{Annotations, Legend};
use arbvis_core::camera::Camera;
use arbvis_core::image::Image;
use arbvis_data::volume::axes::Axis;

/// Which annotations to draw.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Show {
    /// The legends.
    pub legend: bool,
    /// The axes.
    pub axes: bool,
}

/// Register the font plotters draws text in (egui's Ubuntu Light, already a dependency).
pub fn register_font() -> Result<(), AnnotateError> {
    plotters::style::register_font(
        "sans-serif",
        plotters::style::FontStyle::Normal,
        epaint_default_fonts::UBUNTU_LIGHT,
    )
    .map_err(|_| AnnotateError::Font)
}

/// Draw what `show` asks of `annotations` onto `image`, seen from `camera`.
pub fn draw(
    image: &mut Image,
    camera: &Camera,
    annotations: &Annotations,
    show: Show,
) -> Result<(), AnnotateError> {
    if !show.legend && !show.axes {
        return Ok(());
    }
    register_font()?;
    let (w, h) = (image.width, image.height);
    let mut buffer: Vec<u8> = image
        .data
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]].map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8))
        .collect();
    let before = buffer.clone();
    let ink = ink_for(&buffer);
    let backdrop = plotters::style::RGBColor(buffer[0], buffer[1], buffer[2]);
    {
        use plotters::prelude::*;
        let area = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        let size = text_size(h);
        if show.axes {
            if let Some(b) = &annotations.axes {
                // Seen as the layer the box belongs to is drawn.
                let camera = Camera {
                    placement: b.placement,
                    ..*camera
                };
                draw_axes(&area, &camera, [w, h], b.half, &b.axes, size, ink)?;
            }
        }
        if show.legend {
            draw_legends(&area, &annotations.legends, [w, h], size, (ink, backdrop))?;
        }
        area.present().map_err(AnnotateError::Draw)?;
    }
    for (p, (now, was)) in buffer
        .chunks_exact(3)
        .zip(before.chunks_exact(3))
        .enumerate()
    {
        if now != was {
            let px = &mut image.data[4 * p..4 * p + 4];
            for c in 0..3 {
                px[c] = now[c] as f32 / 255.0;
            }
            px[3] = 1.0;
        }
    }
    Ok(())
}

/// White text on a dark picture, black on a light one (its top left pixel, the
/// background where the box leaves a margin).
fn ink_for(rgb: &[u8]) -> plotters::style::RGBColor {
    let luma = 0.299 * rgb[0] as f64 + 0.587 * rgb[1] as f64 + 0.114 * rgb[2] as f64;
    if luma < 128.0 {
        plotters::style::RGBColor(240, 240, 240)
    } else {
        plotters::style::RGBColor(20, 20, 20)
    }
}

type Area<'a> =
    plotters::drawing::DrawingArea<plotters::backend::BitMapBackend<'a>, plotters::coord::Shift>;

fn text(
    area: &Area<'_>,
    s: &str,
    at: (i32, i32),
    size: f64,
    ink: plotters::style::RGBColor,
    anchor: (
        plotters::style::text_anchor::HPos,
        plotters::style::text_anchor::VPos,
    ),
) -> Result<(), AnnotateError> {
    use plotters::prelude::*;
    use plotters::style::text_anchor::Pos;
    let style = ("sans-serif", size)
        .into_font()
        .color(&ink)
        .pos(Pos::new(anchor.0, anchor.1));
    area.draw(&Text::new(s.to_string(), at, style))
        .map_err(AnnotateError::Draw)
}

/// A number written briefly: integers whole, others with four significant digits.
pub fn brief(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e9 {
        format!("{}", v as i64)
    } else {
        arbvis_core::vocab::significant(v)
    }
}

/// The text size of a picture `h` pixels tall (points = pixels).
pub fn text_size(h: u32) -> f64 {
    (h as f64 / 36.0).clamp(11.0, 20.0)
}

/// Where the first legend's colour bar lies on a `w` x `h` picture when the first legend
/// is a bar: its left column, top row, width and height in pixels (column `x` of the
/// bar shows entry `x * 256 / width`).
pub fn first_bar(w: u32, h: u32) -> [i32; 4] {
    let size = text_size(h);
    let width = (w as f64 * 0.3).clamp(60.0, 220.0) as i32;
    let right = w as i32 - (size as i32);
    let line = (size * 1.3) as i32;
    [
        right - width,
        size as i32 + line,
        width,
        (size * 0.9) as i32,
    ]
}

/// The height in pixels of `legend` in the stack (text `size`).
fn legend_height(legend: &Legend, size: f64) -> i32 {
    let line = (size * 1.3) as i32;
    match legend {
        Legend::Bar { .. } => line + (size * 0.9) as i32 + 2 + line + line / 2,
        Legend::Keys { keys, .. } => line + keys.len() as i32 * line + line / 2,
    }
}

/// The legends stacked in the top right corner, over a panel of the background
/// (`colours`: the text's ink and the backdrop).
fn draw_legends(
    area: &Area<'_>,
    legends: &[Legend],
    [w, h]: [u32; 2],
    size: f64,
    (ink, backdrop): (plotters::style::RGBColor, plotters::style::RGBColor),
) -> Result<(), AnnotateError> {
    use plotters::prelude::*;
    use plotters::style::text_anchor::{HPos, VPos};
    let [left, _, width, _] = first_bar(w, h);
    let right = left + width;
    let line = (size * 1.3) as i32;
    let mut y = size as i32;
    if !legends.is_empty() {
        let pad = (size / 2.0) as i32;
        let bottom = y + legends.iter().map(|l| legend_height(l, size)).sum::<i32>();
        area.draw(&Rectangle::new(
            [
                (left - pad, y - pad),
                (right + pad, bottom - line / 2 + pad),
            ],
            backdrop.mix(0.75).filled(),
        ))
        .map_err(AnnotateError::Draw)?;
    }
    for legend in legends {
        match legend {
            Legend::Bar {
                title,
                colours,
                low,
                high,
            } => {
                text(area, title, (left, y), size, ink, (HPos::Left, VPos::Top))?;
                y += line;
                let bar = (size * 0.9) as i32;
                let n = colours.len().max(1) as i32;
                for x in 0..width {
                    let c = colours[((x * n) / width).clamp(0, n - 1) as usize];
                    area.draw(&Rectangle::new(
                        [(left + x, y), (left + x + 1, y + bar)],
                        RGBColor(c[0], c[1], c[2]).filled(),
                    ))
                    .map_err(AnnotateError::Draw)?;
                }
                area.draw(&Rectangle::new([(left - 1, y - 1), (right, y + bar)], ink))
                    .map_err(AnnotateError::Draw)?;
                y += bar + 2;
                text(
                    area,
                    &brief(*low),
                    (left, y),
                    size,
                    ink,
                    (HPos::Left, VPos::Top),
                )?;
                text(
                    area,
                    &brief(*high),
                    (right, y),
                    size,
                    ink,
                    (HPos::Right, VPos::Top),
                )?;
                y += line + line / 2;
            }
            Legend::Keys { title, keys } => {
                text(area, title, (left, y), size, ink, (HPos::Left, VPos::Top))?;
                y += line;
                for (c, name) in keys {
                    let s = (size * 0.8) as i32;
                    area.draw(&Rectangle::new(
                        [(left, y + 1), (left + s, y + 1 + s)],
                        RGBColor(c[0], c[1], c[2]).filled(),
                    ))
                    .map_err(AnnotateError::Draw)?;
                    let at = (left + s + s / 2, y);
                    text(area, name, at, size, ink, (HPos::Left, VPos::Top))?;
                    y += line;
                }
                y += line / 2;
            }
        }
    }
    Ok(())
}

/// Object point `p` on the picture, in pixels from the top left.
fn project(m: &glam::DMat4, p: DVec3, [w, h]: [u32; 2]) -> DVec2 {
    let c = *m * DVec4::new(p.x, p.y, p.z, 1.0);
    let ndc = c.truncate() / c.w;
    DVec2::new(
        (ndc.x + 1.0) / 2.0 * w as f64,
        (1.0 - ndc.y) / 2.0 * h as f64,
    )
}

fn draw_axes(
    area: &Area<'_>,
    camera: &Camera,
    size_px: [u32; 2],
    half: [f64; 3],
    axes: &[Axis; 3],
    size: f64,
    ink: plotters::style::RGBColor,
) -> Result<(), AnnotateError> {
    use plotters::prelude::*;
    use plotters::style::text_anchor::{HPos, VPos};
    let m = camera.view_projection(size_px[0] as f64 / size_px[1] as f64);
    let half = DVec3::from_array(half);
    let centre = project(&m, DVec3::ZERO, size_px);
    for (a, axis) in axes.iter().enumerate() {
        // The four edges along axis a, at the corners of the other two; the one whose
        // middle lies farthest from the box's centre on screen (lowest on a tie).
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let edge = |sb: f64, sc: f64| {
            let mut lo = DVec3::ZERO;
            lo[a] = -half[a];
            lo[b] = sb * half[b];
            lo[c] = sc * half[c];
            let mut hi = lo;
            hi[a] = half[a];
            (project(&m, lo, size_px), project(&m, hi, size_px))
        };
        let edges =
            [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)].map(|(sb, sc)| edge(sb, sc));
        let score = |(p, q): &(DVec2, DVec2)| {
            let mid = (*p + *q) / 2.0;
            (mid - centre).length() + 1e-3 * mid.y
        };
        let (p, q) = edges
            .iter()
            .copied()
            .max_by(|x, y| score(x).total_cmp(&score(y)))
            .expect("four edges");
        if (q - p).length() < 4.0 * size {
            // Seen end on (a flat cloud's height from above): too short to label.
            continue;
        }
        let mid = (p + q) / 2.0;
        let out = (mid - centre).try_normalize().unwrap_or(DVec2::Y);
        let px = |v: DVec2| (v.x.round() as i32, v.y.round() as i32);
        area.draw(&PathElement::new(vec![px(p), px(q)], ink))
            .map_err(AnnotateError::Draw)?;
        let anchor = (
            if out.x > 0.3 {
                HPos::Left
            } else if out.x < -0.3 {
                HPos::Right
            } else {
                HPos::Center
            },
            if out.y > 0.3 {
                VPos::Top
            } else if out.y < -0.3 {
                VPos::Bottom
            } else {
                VPos::Center
            },
        );
        for tick in axis.ticks(4) {
            let at = p + (q - p) * tick.at;
            area.draw(&PathElement::new(
                vec![px(at), px(at + out * size * 0.4)],
                ink,
            ))
            .map_err(AnnotateError::Draw)?;
            text(
                area,
                &tick.label,
                px(at + out * size * 0.6),
                size * 0.85,
                ink,
                anchor,
            )?;
        }
        text(
            area,
            &axis.name,
            px(mid + out * size * 2.0),
            size,
            ink,
            anchor,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_written_briefly() {
        for (v, want) in [
            (296.0, "296"),
            (-6000.0, "-6000"),
            (0.35537, "0.3554"),
            (1.6412404, "1.641"),
            (-10239.5, "-10240"),
            (2.5e-5, "0.000025"),
        ] {
            assert_eq!(brief(v), want, "{v}");
        }
    }
}
