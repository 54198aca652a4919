//! Text in a pixel buffer: the 8x8 bitmap font of `font8x8`, scaled by whole pixels.

use crate::Frame;
use font8x8::UnicodeFonts;

/// Width (and height) of a glyph at scale 1, pixels.
pub const GLYPH: usize = 8;

/// Draws `text` with its top left corner at (`x`, `y`), each glyph `GLYPH * scale` pixels
/// square, in `colour` (0RGB); characters the font lacks are drawn as `?`. Clipped to the
/// frame. Returns the x just past the last glyph.
pub fn draw(frame: &mut Frame, x: usize, y: usize, scale: usize, colour: u32, text: &str) -> usize {
    let mut x0 = x;
    for ch in text.chars() {
        let glyph = font8x8::BASIC_FONTS
            .get(ch)
            .or_else(|| font8x8::BASIC_FONTS.get('?'))
            .unwrap_or([0; 8]);
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..GLYPH {
                // Bit 0 is the leftmost pixel.
                if bits >> col & 1 == 1 {
                    frame.fill_rect(x0 + col * scale, y + row * scale, scale, scale, colour);
                }
            }
        }
        x0 += GLYPH * scale;
    }
    x0
}
