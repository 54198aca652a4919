//! Pictures: a block rendered covers the pixels of its area, coloured along the map; PNG and
//! GIF files decode back (with the `png` and `gif` crates' decoders) to the frames written.

use mpm_gimp::{HeapBuffer, MaterialDef, Vec3, World, WorldDef};
use mpm_gimp_output::picture::{render, value_range, write_gif, write_png, Colour, Picture};

const BACKGROUND: [u8; 3] = [246, 246, 242];

fn block(buf: &mut Option<HeapBuffer>) -> World<'_> {
    let def = WorldDef {
        cells: [40, 20, 1],
        cell_size: 0.025,
        ..WorldDef::DEFAULT
    };
    let bytes = mpm_gimp::memory_requirements(&def).unwrap().bytes;
    let buf = buf.insert(HeapBuffer::new(bytes));
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m = w.add_material(&MaterialDef::DEFAULT).unwrap();
    // 0.4 m x 0.2 m, moving right at 1 m/s.
    w.fill_box(
        Vec3::new(0.3, 0.15, 0.0),
        Vec3::new(0.7, 0.35, 0.0),
        m,
        Vec3::new(1.0, 0.0, 0.0),
    )
    .unwrap();
    w
}

fn painted(p: &Picture) -> Vec<(u32, u32, [u8; 3])> {
    (0..p.height)
        .flat_map(|y| (0..p.width).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let at = 3 * (y * p.width + x) as usize;
            let c = [p.rgb[at], p.rgb[at + 1], p.rgb[at + 2]];
            (c != BACKGROUND && c != [90, 90, 90]).then_some((x, y, c))
        })
        .collect()
}

/// A 0.4 m x 0.2 m block on a 1 m x 0.5 m grid rendered 400 px wide (400 px per metre) covers
/// its own 160 x 80 px (within a particle's disc at its edges: 10 % of the area) and no pixel
/// outside it, in the colour of its uniform speed.
#[test]
fn a_block_covers_its_area_in_its_colour() {
    let mut buf = None;
    let w = block(&mut buf);
    let p = render(&w, Colour::Speed, (0.0, 2.0), 400);
    assert_eq!((p.width, p.height), (400, 200));
    let px = painted(&p);
    let area = 160.0 * 80.0;
    assert!(
        ((px.len() as f64 - area) / area).abs() < 0.1,
        "{} px painted",
        px.len()
    );
    // The block spans x 120..280 px and y (from the top) 60..140 px, give or take a disc.
    for &(x, y, c) in &px {
        assert!(
            (117..=283).contains(&x) && (57..=143).contains(&y),
            "pixel {x} {y} painted"
        );
        assert_eq!(c, px[0].2, "one speed, one colour");
    }
    // Speed 1 of 0..2 is the middle of the map, neither end.
    let ends = [
        render(&w, Colour::Speed, (1.0, 2.0), 40),
        render(&w, Colour::Speed, (0.0, 1.0), 40),
    ];
    let colours: Vec<[u8; 3]> = ends.iter().map(|p| painted(p)[0].2).collect();
    assert_ne!(colours[0], colours[1]);
    assert_ne!(px[0].2, colours[0]);
    assert_ne!(px[0].2, colours[1]);
    let (lo, hi) = value_range(&w, Colour::Speed);
    assert!(
        (lo - 1.0).abs() < 1e-6 && (hi - 1.0).abs() < 1e-6,
        "{lo} {hi}"
    );
}

/// PNG and GIF files decode back to what was written: the PNG pixel for pixel, the GIF with
/// every frame at its size (its colours are quantised to a palette).
#[test]
fn png_and_gif_decode_back() {
    let mut buf = None;
    let mut w = block(&mut buf);
    let mut frames = vec![];
    for _ in 0..3 {
        frames.push(render(&w, Colour::Speed, (0.0, 2.0), 120));
        w.step(1.0 / 60.0).unwrap();
    }
    let mut png_bytes = vec![];
    write_png(&mut png_bytes, &frames[0]).unwrap();
    let decoder = png::Decoder::new(&png_bytes[..]);
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut pixels).unwrap();
    assert_eq!(
        (info.width, info.height),
        (frames[0].width, frames[0].height)
    );
    assert_eq!(&pixels[..info.buffer_size()], &frames[0].rgb[..]);
    let mut gif_bytes = vec![];
    write_gif(&mut gif_bytes, &frames, 3).unwrap();
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(&gif_bytes[..]).unwrap();
    let mut count = 0;
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        assert_eq!(
            (frame.width as u32, frame.height as u32),
            (frames[0].width, frames[0].height)
        );
        assert_eq!(frame.delay, 3);
        // Painted pixels stay painted: the background is one palette entry of its own.
        let bg = frame
            .buffer
            .chunks(4)
            .filter(|c| c[..3] == BACKGROUND)
            .count();
        let expected = frames[count]
            .rgb
            .chunks(3)
            .filter(|c| *c == BACKGROUND)
            .count();
        assert!(
            bg.abs_diff(expected) <= expected / 100,
            "frame {count}: {bg} vs {expected}"
        );
        count += 1;
    }
    assert_eq!(count, frames.len());
}
