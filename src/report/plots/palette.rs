//! Palette PNGs: a chart has few colours (white, axes, a handful of series colours and their
//! anti-aliased edges), so an 8-bit indexed PNG holds it in a fraction of an RGB PNG's bytes.
//! Up to 256 distinct colours the encoding is exact; beyond that the 256 most frequent colours
//! form the palette and every other colour takes its nearest palette entry (squared RGB
//! distance, ties to the more frequent), a deterministic choice that moves only the rarest
//! anti-aliasing pixels.

use std::collections::HashMap;

/// The most palette entries an 8-bit indexed PNG can hold.
const MAX_COLOURS: usize = 256;

/// Encode an RGB buffer (`w * h * 3` bytes, rows top to bottom) as an 8-bit indexed PNG.
pub(crate) fn encode(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, png::EncodingError> {
    let (palette, indices) = quantise(rgb);
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_palette(palette.iter().flatten().copied().collect::<Vec<u8>>());
        enc.set_compression(png::Compression::Best);
        enc.set_filter(png::FilterType::NoFilter);
        enc.set_adaptive_filter(png::AdaptiveFilterType::NonAdaptive);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&indices)?;
    }
    Ok(out)
}

/// The palette (at most [`MAX_COLOURS`] colours, most frequent first, ties by colour value) and
/// each pixel's index into it.
fn quantise(rgb: &[u8]) -> (Vec<[u8; 3]>, Vec<u8>) {
    let mut counts: HashMap<[u8; 3], u64> = HashMap::new();
    for p in rgb.chunks_exact(3) {
        *counts.entry([p[0], p[1], p[2]]).or_insert(0) += 1;
    }
    let mut by_count: Vec<([u8; 3], u64)> = counts.into_iter().collect();
    by_count.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let palette: Vec<[u8; 3]> = by_count.iter().take(MAX_COLOURS).map(|c| c.0).collect();
    let index: HashMap<[u8; 3], u8> =
        by_count.iter().map(|&(colour, _)| (colour, nearest(&palette, colour))).collect();
    let indices = rgb.chunks_exact(3).map(|p| index[&[p[0], p[1], p[2]]]).collect();
    (palette, indices)
}

/// The index of the palette entry nearest to `c` (the first, i.e. most frequent, on a tie).
fn nearest(palette: &[[u8; 3]], c: [u8; 3]) -> u8 {
    let d = |p: &[u8; 3]| -> u32 {
        (0..3).map(|k| (i32::from(p[k]) - i32::from(c[k])).pow(2) as u32).sum()
    };
    let best = (0..palette.len()).min_by_key(|&i| (d(&palette[i]), i)).unwrap_or(0);
    // At most MAX_COLOURS = 256 entries, so every index fits in a byte.
    u8::try_from(best).unwrap_or(u8::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
        let mut dec = png::Decoder::new(bytes);
        dec.set_transformations(png::Transformations::EXPAND);
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    #[test]
    fn few_colours_round_trip_exactly() {
        let (w, h) = (37u32, 11u32);
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|k| {
                let c = (k % 200) as u8;
                [c, 255 - c, c / 2]
            })
            .collect();
        let bytes = encode(&rgb, w, h).unwrap();
        assert_eq!(decode(&bytes), (w, h, rgb));
    }

    #[test]
    fn many_colours_keep_the_frequent_ones_and_map_the_rest_to_the_nearest() {
        // 301 colours: white in most pixels, 255 greys of two pixels each, and 45 colours of one
        // pixel each, one step of blue from a grey.
        let mut rgb = vec![255u8; 3 * 1000];
        for k in 0..255usize {
            let g = k as u8;
            rgb[6 * k..6 * k + 6].copy_from_slice(&[g, g, g, g, g, g]);
        }
        for k in 0..45usize {
            let g = k as u8;
            rgb[1530 + 3 * k..1533 + 3 * k].copy_from_slice(&[g, g, g + 1]);
        }
        let (palette, indices) = quantise(&rgb);
        assert_eq!(palette.len(), MAX_COLOURS);
        assert_eq!(palette[0], [255, 255, 255], "the most frequent colour comes first");
        for (p, &i) in rgb.chunks_exact(3).zip(&indices) {
            let got = palette[i as usize];
            let err: i32 = (0..3).map(|k| (i32::from(got[k]) - i32::from(p[k])).abs()).sum();
            assert!(err <= 1, "{p:?} -> {got:?}");
        }
        assert_eq!(quantise(&rgb), (palette, indices), "deterministic");
    }
}
