//! Fonts, colours and sizes shared by every chart, so a report's pictures look like one family.
//!
//! Colours follow the Okabe-Ito palette (distinguishable with the common colour-vision
//! deficiencies); the DNSOM bottom and top views (thesis Section 4.2.3) use its blue and
//! vermillion, the two hues furthest apart in it.

use super::DrawError;
use plotters::style::IntoFont;
use plotters::style::{register_font, FontStyle, RGBColor, TextStyle};
use std::sync::OnceLock;

/// The font family name every chart asks plotters for.
pub(crate) const FONT: &str = "sans-serif";

/// Registers DejaVu Sans (regular and bold) as `sans-serif` once per process.
pub(crate) fn ensure_fonts() -> Result<(), DrawError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
            && register_font(FONT, FontStyle::Bold, dejavu::sans::bold()).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(DrawError::Font)
    }
}

// Sizes are even: plotters 0.3.7's ab_glyph text places each glyph at
// `(size / 2 + glyph top) as i32`, which at odd sizes rounds glyphs above and below the middle
// in opposite directions (a decimal point then floats a pixel above the baseline).

/// Chart title size (pixels).
pub(crate) const TITLE_PX: f64 = 22.0;
/// Axis description size (pixels).
pub(crate) const AXIS_DESC_PX: f64 = 16.0;
/// Tick label and legend size (pixels).
pub(crate) const LABEL_PX: f64 = 14.0;
/// Caption size of an overview panel (pixels).
pub(crate) const CAPTION_PX: f64 = 16.0;
/// The smallest size a title shrinks to before it wraps ([`fitted_title`]).
pub(crate) const MIN_TITLE_PX: f64 = 10.0;

/// Size of a 2-D chart (line chart, box plot) in pixels.
pub(crate) const CHART_SIZE: (u32, u32) = (960, 600);
/// Side of one overview panel (pixels), caption included.
pub(crate) const PANEL_PX: u32 = 200;
/// Default size of a single mesh picture.
pub(crate) const MESH_SIZE: (u32, u32) = (480, 420);

/// Okabe-Ito black.
pub(crate) const BLACK: RGBColor = RGBColor(0, 0, 0);
/// Okabe-Ito orange.
pub(crate) const ORANGE: RGBColor = RGBColor(230, 159, 0);
/// Okabe-Ito sky blue.
pub(crate) const SKY_BLUE: RGBColor = RGBColor(86, 180, 233);
/// Okabe-Ito bluish green.
pub(crate) const GREEN: RGBColor = RGBColor(0, 158, 115);
/// Okabe-Ito blue.
pub(crate) const BLUE: RGBColor = RGBColor(0, 114, 178);
/// Okabe-Ito vermillion.
pub(crate) const VERMILLION: RGBColor = RGBColor(213, 94, 0);
/// Okabe-Ito reddish purple.
pub(crate) const PURPLE: RGBColor = RGBColor(204, 121, 167);
/// Neutral grey for baselines.
pub(crate) const GREY: RGBColor = RGBColor(110, 110, 110);
/// Axis panels and grid lines.
pub(crate) const GRID: RGBColor = RGBColor(225, 225, 225);

/// DNSOM bottom view (k = 0 side, thesis Figure 4.4).
pub(crate) const DNSOM_BOTTOM: RGBColor = BLUE;
/// DNSOM top view (k = 2 side, thesis Figure 4.4).
pub(crate) const DNSOM_TOP: RGBColor = VERMILLION;

/// Series colours in the order they are handed out for unnamed series.
pub(crate) const CYCLE: [RGBColor; 8] =
    [BLUE, VERMILLION, GREEN, ORANGE, PURPLE, SKY_BLUE, BLACK, GREY];

/// The `i`-th colour of [`CYCLE`] (wrapping).
pub(crate) fn cycle_colour(i: usize) -> RGBColor {
    CYCLE[i % CYCLE.len()]
}

/// Colours for optimisers somnurbs does not know (externals logged from Python, such as CMA-ES),
/// handed out in their order among such names: none is a registered optimiser's, the exact
/// optimum's or B's (Okabe-Ito's yellow, then Paul Tol's muted scheme and two darks).
pub(crate) const EXTRA: [RGBColor; 8] = [
    RGBColor(51, 34, 136),
    RGBColor(204, 102, 119),
    RGBColor(68, 170, 153),
    RGBColor(153, 153, 51),
    RGBColor(136, 34, 85),
    RGBColor(140, 86, 75),
    RGBColor(240, 228, 66),
    RGBColor(47, 79, 79),
];

/// The colour of the series `name` among the series `names` of one chart: an optimiser's own
/// ([`optimiser_colour`]), else the [`EXTRA`] colour of its place among the names that have none,
/// so that no two optimisers of a chart share a colour (up to eight unknown ones).
pub(crate) fn series_colour<S: AsRef<str>>(name: &str, names: &[S]) -> RGBColor {
    if let Some(c) = optimiser_colour(name) {
        return c;
    }
    let unknown = names.iter().map(AsRef::as_ref).filter(|n| optimiser_colour(n).is_none());
    let mut seen: Vec<&str> = Vec::new();
    for n in unknown {
        if !seen.contains(&n) {
            seen.push(n);
        }
    }
    let k = seen.iter().position(|n| *n == name).unwrap_or(seen.len());
    EXTRA[k % EXTRA.len()]
}

/// One colour per optimiser (case-insensitive): each registered one's (`optim::REGISTRY`), and
/// exact (the certified convex optimum) and b (approach B's least-squares control points, the
/// starting point).
/// Unknown names get `None`; use [`cycle_colour`] for them.
pub(crate) fn optimiser_colour(name: &str) -> Option<RGBColor> {
    match name.trim().to_ascii_lowercase().as_str() {
        "exact" => Some(BLACK),
        "b" => Some(GREY),
        other => {
            crate::optim::registered(other).map(|r| RGBColor(r.colour[0], r.colour[1], r.colour[2]))
        }
    }
}

/// Regular text of `px` pixels.
pub(crate) fn text(px: f64) -> TextStyle<'static> {
    (FONT, px).into_font().into()
}

/// Bold text of `px` pixels.
pub(crate) fn bold(px: f64) -> TextStyle<'static> {
    (FONT, px).into_font().style(FontStyle::Bold).into()
}

/// Pixel width of `text` in `style` on `area`.
pub(crate) fn text_width<
    DB: plotters::prelude::DrawingBackend,
    CT: plotters::coord::CoordTranslate,
>(
    area: &plotters::prelude::DrawingArea<DB, CT>,
    text: &str,
    style: &TextStyle,
) -> Result<i32, DrawError>
where
    DB::ErrorType: Send + Sync,
{
    area.estimate_text_size(text, style)
        .map(|(w, _)| w as i32)
        .map_err(|e| DrawError::Backend(e.to_string()))
}

/// A bold title that fits `width` pixels on `area`: one line at the largest even size from `px`
/// down to [`MIN_TITLE_PX`] at which it fits, else its words wrapped into lines at that smallest
/// size (a single word wider than `width` keeps a line of its own). Returns the lines and the size.
pub(crate) fn fitted_title<
    DB: plotters::prelude::DrawingBackend,
    CT: plotters::coord::CoordTranslate,
>(
    area: &plotters::prelude::DrawingArea<DB, CT>,
    title: &str,
    px: f64,
    width: i32,
) -> Result<(Vec<String>, f64), DrawError>
where
    DB::ErrorType: Send + Sync,
{
    let fits = |t: &str, px: f64| -> Result<bool, DrawError> {
        Ok(text_width(area, t, &bold(px))? <= width)
    };
    let mut size = px;
    while size > MIN_TITLE_PX && !fits(title, size)? {
        size = (size - 2.0).max(MIN_TITLE_PX);
    }
    if fits(title, size)? {
        return Ok((vec![title.to_string()], size));
    }
    let mut lines: Vec<String> = Vec::new();
    for word in title.split(' ') {
        match lines.last_mut() {
            Some(line) if fits(&format!("{line} {word}"), size)? => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    Ok((lines, size))
}

/// `text` cut to at most `max` characters (an ellipsis marks the cut).
pub(crate) fn truncate(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        text.to_string()
    } else {
        let mut s: String = text.chars().take(max.saturating_sub(1)).collect();
        s.push('…');
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fonts_register_and_are_idempotent() {
        ensure_fonts().unwrap();
        ensure_fonts().unwrap();
    }

    /// An overview panel's title keeps its size when it fits, shrinks when it does not (Appendix
    /// I's "chord_length 18x18 B (3.1954e1)" in a 200-pixel panel), and wraps at the smallest size.
    #[test]
    fn a_title_shrinks_then_wraps_to_fit_its_width() {
        use plotters::prelude::*;
        ensure_fonts().unwrap();
        let mut buf = vec![0u8; 200 * 200 * 3];
        let area = BitMapBackend::with_buffer(&mut buf, (200, 200)).into_drawing_area();
        let width = |t: &str, px: f64| text_width(&area, t, &bold(px)).unwrap();
        let short = "cube CKSOM 10x10";
        assert_eq!(
            fitted_title(&area, short, CAPTION_PX, 190).unwrap(),
            (vec![short.to_string()], CAPTION_PX)
        );
        let long = "chord_length 18x18 B (3.1954e1)";
        assert!(width(long, CAPTION_PX) > 190, "the case is one that did not fit");
        let (lines, px) = fitted_title(&area, long, CAPTION_PX, 190).unwrap();
        assert_eq!(lines, vec![long.to_string()]);
        assert!((MIN_TITLE_PX..CAPTION_PX).contains(&px) && width(long, px) <= 190, "{px}");
        assert_eq!(px % 2.0, 0.0, "sizes stay even");
        let longer = "GA: (MIN - B) x26990, max 6e-5, beside the grey approach B, the start";
        let (lines, px) = fitted_title(&area, longer, CAPTION_PX, 190).unwrap();
        assert!(lines.len() > 1 && px == MIN_TITLE_PX, "{lines:?}");
        assert!(lines.iter().all(|l| width(l, px) <= 190), "{lines:?}");
        assert_eq!(lines.join(" "), longer);
    }

    #[test]
    fn optimiser_colours_are_distinct() {
        let names = ["ga", "de", "pso", "csa", "icsa", "exact", "b"];
        let cs: Vec<RGBColor> = names.iter().map(|n| optimiser_colour(n).unwrap()).collect();
        for i in 0..cs.len() {
            for j in 0..i {
                assert_ne!(cs[i], cs[j], "{} and {} share a colour", names[i], names[j]);
            }
        }
        assert_eq!(optimiser_colour(" DE "), Some(BLUE));
        // Externals: each its own colour, none of the named ones', whatever their place.
        let chart = ["cma-es", "ga", "scipy-de", "de", "nelder-mead", "exact", "b"];
        let got: Vec<RGBColor> = chart.iter().map(|n| series_colour(n, &chart)).collect();
        for i in 0..got.len() {
            for j in 0..i {
                assert_ne!(got[i], got[j], "{} and {} share a colour", chart[i], chart[j]);
            }
        }
        for (k, extra) in EXTRA.iter().enumerate() {
            assert!(!cs.contains(extra), "EXTRA[{k}] is a named optimiser's colour");
            assert!(!EXTRA[..k].contains(extra), "EXTRA[{k}] repeats");
        }
        assert_eq!(series_colour("ga", &chart), ORANGE);
        assert_eq!(series_colour("cma-es", &chart), EXTRA[0]);
        assert_eq!(optimiser_colour("sa"), None);
    }

    /// Up to eight externals beside the named optimisers: each its own colour, none the colour of
    /// GA, DE, PSO, CSA, ICSA, B or the optimum, whatever their order among the names.
    #[test]
    fn eight_externals_take_eight_colours_none_reserved() {
        let reserved = ["ga", "de", "pso", "csa", "icsa", "exact", "b"];
        let taken: Vec<RGBColor> = reserved.iter().map(|n| optimiser_colour(n).unwrap()).collect();
        for k in 1..=EXTRA.len() {
            let externals: Vec<String> = (0..k).map(|i| format!("ext{i}")).collect();
            let mut chart: Vec<&str> = externals.iter().map(String::as_str).collect();
            chart.splice(0..0, reserved);
            let n = chart.len();
            chart.rotate_left(k % n);
            let got: Vec<RGBColor> = externals.iter().map(|n| series_colour(n, &chart)).collect();
            for (i, c) in got.iter().enumerate() {
                assert!(!taken.contains(c), "{} of {k} takes a reserved colour", externals[i]);
                assert!(!got[..i].contains(c), "{} of {k} repeats a colour", externals[i]);
            }
        }
    }

    #[test]
    fn dnsom_views_are_far_apart() {
        let d = |a: RGBColor, b: RGBColor| {
            let f = |x: u8, y: u8| (x as f64 - y as f64).powi(2);
            (f(a.0, b.0) + f(a.1, b.1) + f(a.2, b.2)).sqrt()
        };
        assert!(d(DNSOM_BOTTOM, DNSOM_TOP) > 200.0);
    }
}
