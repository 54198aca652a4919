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

/// `text` broken at spaces into at most `lines` lines of at most `width` pixels each at
/// `scale`; a word longer than a line is cut, and if the text does not fit, the last line
/// ends in "..". Returns the lines and whether they hold all of `text`.
pub fn wrap(text: &str, width: usize, scale: usize, lines: usize) -> (Vec<String>, bool) {
    let per_line = width / (GLYPH * scale);
    let (mut out, mut current, mut whole) = (Vec::<String>::new(), String::new(), true);
    for word in text.split_whitespace() {
        let len = current.chars().count();
        if len > 0 && len + 1 + word.chars().count() <= per_line {
            current.push(' ');
            current.push_str(word);
            continue;
        }
        if len > 0 {
            out.push(std::mem::take(&mut current));
        }
        whole &= word.chars().count() <= per_line;
        current = word.chars().take(per_line).collect();
    }
    if !current.is_empty() {
        out.push(current);
    }
    if out.len() > lines {
        whole = false;
        out.truncate(lines);
        if let Some(last) = out.last_mut() {
            let keep = per_line.saturating_sub(2).min(last.chars().count());
            *last = last.chars().take(keep).collect::<String>() + "..";
        }
    }
    (out, whole)
}
