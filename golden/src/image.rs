//! Float RGB images, 8-bit quantisation and PNG input/output.
//!
//! [`Image`] is what the renderers produce: linear float RGB, row-major, one `[r, g, b]` per
//! pixel. [`Rgb8Image`] is its 8-bit form, the one that is written to and read from PNG files and
//! that the metrics compare.
//!
//! Quantisation rule ([`quantize_channel`]): clamp to `[0, 1]`, then round half up,
//! `floor(v * 255 + 0.5)`. This is the rule of the common PyTorch image savers
//! (`mul(255).add(0.5).clamp(0, 255)` then a truncating cast) and it is the one that matches the
//! shared reference renders `biker_ref_*.png`: against them, rounding gives a clearly higher PSNR
//! than truncation (see `golden/tests/render_biker.rs`, which checks both).

use crate::error::{InputError, InputResult};
use std::io::{BufReader, BufWriter, Read};
use std::path::Path;

/// A linear float RGB image, row-major, with no particular range (renders are normally in
/// `[0, 1]` but nothing clamps them).
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels, row-major (`data[y * width + x]`), `[r, g, b]` each.
    pub data: Vec<[f32; 3]>,
}

impl Image {
    /// A black image of the given size.
    pub fn new(width: u32, height: u32) -> Self {
        Image { width, height, data: vec![[0.0; 3]; width as usize * height as usize] }
    }

    /// The pixel at column `x`, row `y` (panics when outside the image).
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}x{}", self.width, self.height);
        self.data[y as usize * self.width as usize + x as usize]
    }

    /// Quantises every channel with [`quantize_channel`] into an 8-bit image.
    pub fn to_rgb8(&self) -> Rgb8Image {
        let data = self.data.iter().flat_map(|p| p.map(quantize_channel)).collect();
        Rgb8Image { width: self.width, height: self.height, data }
    }
}

/// One float channel to 8 bits: clamp to `[0, 1]`, then round half up (`floor(v * 255 + 0.5)`).
/// NaN maps to 0.
pub fn quantize_channel(v: f32) -> u8 {
    let c = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (c * 255.0 + 0.5).floor() as u8
}

/// An 8-bit RGB image, row-major, three bytes per pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rgb8Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` bytes: `r g b` of pixel `(x, y)` at `3 * (y * width + x)`.
    pub data: Vec<u8>,
}

/// Largest decoded image [`Rgb8Image::read_png`] accepts, in bytes (guards against bombs). It is
/// checked against the size in the PNG header before any pixel buffer is allocated.
pub const MAX_PNG_DECODED_BYTES: usize = 1 << 28;

impl Rgb8Image {
    /// A black image of the given size.
    pub fn new(width: u32, height: u32) -> Self {
        Rgb8Image { width, height, data: vec![0; width as usize * height as usize * 3] }
    }

    /// The `[r, g, b]` of pixel `(x, y)` (panics when outside the image).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}x{}", self.width, self.height);
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Reads a PNG file. See [`Rgb8Image::decode_png`] for what is accepted.
    pub fn read_png(path: impl AsRef<Path>) -> InputResult<Rgb8Image> {
        let path = path.as_ref();
        let file =
            std::fs::File::open(path).map_err(|e| InputError::new(path, format!("cannot open: {e}")))?;
        Self::decode_png(BufReader::new(file), path)
    }

    /// Decodes a PNG stream; `path` only names the source in errors.
    ///
    /// Any colour type and bit depth is accepted and converted to 8-bit RGB: palette and
    /// sub-byte greys are expanded, 16-bit samples keep their high byte, grey is replicated to
    /// the three channels and alpha is dropped (not composited). Only the first frame of an
    /// animated PNG is read. Malformed data gives an [`InputError`], never a panic.
    pub fn decode_png<R: Read>(reader: R, path: &Path) -> InputResult<Rgb8Image> {
        let bad = |e: png::DecodingError| InputError::new(path, format!("not a readable PNG: {e}"));
        let mut decoder = png::Decoder::new(reader);
        decoder.set_transformations(png::Transformations::normalize_to_color8());
        decoder.set_limits(png::Limits { bytes: MAX_PNG_DECODED_BYTES });
        let mut reader = decoder.read_info().map_err(bad)?;
        // The decoder's limit does not cover the output buffer allocated here, so check the
        // header's size first: a tiny file may declare a gigapixel image.
        let (width, height) = reader.info().size();
        let (color, depth) = reader.output_color_type();
        let bytes_per_pixel = (color.samples().max(3) * (depth as usize).div_ceil(8)) as u128;
        let need = width as u128 * height as u128 * bytes_per_pixel;
        if need > MAX_PNG_DECODED_BYTES as u128 {
            return Err(InputError::new(
                path,
                format!(
                    "PNG is {width}x{height}: decoding it needs {need} bytes, more than the limit of \
                     {MAX_PNG_DECODED_BYTES} bytes"
                ),
            ));
        }
        let mut buf = vec![0u8; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).map_err(bad)?;
        if info.bit_depth != png::BitDepth::Eight {
            return Err(InputError::new(path, format!("unsupported PNG bit depth {:?}", info.bit_depth)));
        }
        let channels = match info.color_type {
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            png::ColorType::Indexed => {
                return Err(InputError::new(path, "palette PNG could not be expanded to RGB"));
            }
        };
        let (w, h) = (info.width as usize, info.height as usize);
        let mut data = Vec::with_capacity(w * h * 3);
        for row in buf[..info.buffer_size()].chunks_exact(info.line_size).take(h) {
            for px in row[..w * channels].chunks_exact(channels) {
                match channels {
                    1 | 2 => data.extend_from_slice(&[px[0]; 3]),
                    _ => data.extend_from_slice(&px[..3]),
                }
            }
        }
        if data.len() != w * h * 3 {
            return Err(InputError::new(path, "PNG image data is shorter than its header says"));
        }
        Ok(Rgb8Image { width: info.width, height: info.height, data })
    }

    /// Writes the image as an 8-bit RGB PNG.
    pub fn write_png(&self, path: impl AsRef<Path>) -> InputResult<()> {
        let path = path.as_ref();
        if self.data.len() != self.width as usize * self.height as usize * 3 {
            return Err(InputError::new(path, "image buffer size does not match its dimensions"));
        }
        let err = |e: &dyn std::fmt::Display| InputError::new(path, format!("cannot write PNG: {e}"));
        let file = std::fs::File::create(path).map_err(|e| err(&e))?;
        let mut encoder = png::Encoder::new(BufWriter::new(file), self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| err(&e))?;
        writer.write_image_data(&self.data).map_err(|e| err(&e))?;
        writer.finish().map_err(|e| err(&e))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn temp_path(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("neo_image_{}_{name}", std::process::id()))
    }

    fn encode(w: u32, h: u32, color: png::ColorType, depth: png::BitDepth, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, w, h);
            enc.set_color(color);
            enc.set_depth(depth);
            if color == png::ColorType::Indexed {
                enc.set_palette(vec![10, 20, 30, 200, 100, 50]);
            }
            let mut wr = enc.write_header().unwrap();
            wr.write_image_data(data).unwrap();
        }
        out
    }

    #[test]
    fn quantisation_rounds_half_up_and_clamps() {
        assert_eq!(quantize_channel(-1.0), 0);
        assert_eq!(quantize_channel(f32::NAN), 0);
        assert_eq!(quantize_channel(2.0), 255);
        assert_eq!(quantize_channel(1.0), 255);
        // 0.5 / 255 sits exactly between 0 and 1 (up to f32 rounding): just above rounds up.
        assert_eq!(quantize_channel(0.51 / 255.0), 1);
        assert_eq!(quantize_channel(0.49 / 255.0), 0);
        assert_eq!(quantize_channel(100.6 / 255.0), 101);
        assert_eq!(quantize_channel(100.4 / 255.0), 100);
    }

    /// A tiny PNG whose header declares 100000x100000 pixels is an error naming the file, checked
    /// before the 30 GB output buffer is allocated (it used to abort the process).
    #[test]
    fn huge_declared_size_is_an_error_before_allocating() {
        let small = encode(1, 1, png::ColorType::Rgb, png::BitDepth::Eight, &[1, 2, 3]);
        let mut huge = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut huge, 100_000, 100_000);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let wr = enc.write_header().unwrap();
            std::mem::forget(wr); // keep only the signature and IHDR
        }
        // Signature (8) and IHDR (25) of the huge header, then the small image's IDAT and IEND.
        huge.truncate(33);
        huge.extend_from_slice(&small[33..]);
        let e = Rgb8Image::decode_png(&huge[..], Path::new("huge.png")).unwrap_err().to_string();
        assert!(e.starts_with("huge.png: PNG is 100000x100000: decoding it needs 30000000000 bytes"), "{e}");
        // Widths whose byte count overflows 32 bits are caught too.
        let mut wide = Vec::new();
        {
            let enc = png::Encoder::new(&mut wide, u32::MAX / 2, 1);
            std::mem::forget(enc.write_header().unwrap());
        }
        wide.truncate(33);
        wide.extend_from_slice(&small[33..]);
        let e = Rgb8Image::decode_png(&wide[..], Path::new("wide.png")).unwrap_err().to_string();
        assert!(e.starts_with("wide.png: "), "{e}");
    }

    #[test]
    fn png_round_trip() {
        let mut img = Image::new(5, 3);
        for (i, p) in img.data.iter_mut().enumerate() {
            *p = [i as f32 / 15.0, 1.0 - i as f32 / 15.0, 0.5];
        }
        let rgb = img.to_rgb8();
        assert_eq!(rgb.pixel(4, 2), [quantize_channel(14.0 / 15.0), quantize_channel(1.0 / 15.0), 128]);
        let path = temp_path("rt.png");
        rgb.write_png(&path).unwrap();
        let back = Rgb8Image::read_png(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(back, rgb);
    }

    #[test]
    fn other_colour_types_are_converted() {
        let p = Path::new("mem.png");
        let gray = encode(2, 1, png::ColorType::Grayscale, png::BitDepth::Eight, &[7, 9]);
        let img = Rgb8Image::decode_png(&gray[..], p).unwrap();
        assert_eq!(img.data, vec![7, 7, 7, 9, 9, 9]);
        let rgba = encode(1, 2, png::ColorType::Rgba, png::BitDepth::Eight, &[1, 2, 3, 4, 5, 6, 7, 8]);
        assert_eq!(Rgb8Image::decode_png(&rgba[..], p).unwrap().data, vec![1, 2, 3, 5, 6, 7]);
        let rgb16 =
            encode(1, 1, png::ColorType::Rgb, png::BitDepth::Sixteen, &[0x12, 0x34, 0xab, 0xcd, 0xff, 0]);
        assert_eq!(Rgb8Image::decode_png(&rgb16[..], p).unwrap().data, vec![0x12, 0xab, 0xff]);
        let pal = encode(2, 1, png::ColorType::Indexed, png::BitDepth::Eight, &[1, 0]);
        assert_eq!(Rgb8Image::decode_png(&pal[..], p).unwrap().data, vec![200, 100, 50, 10, 20, 30]);
        // 1-bit grey expands to 0 / 255.
        let g1 = encode(3, 1, png::ColorType::Grayscale, png::BitDepth::One, &[0b1010_0000]);
        assert_eq!(
            Rgb8Image::decode_png(&g1[..], p).unwrap().data,
            vec![255, 255, 255, 0, 0, 0, 255, 255, 255]
        );
    }

    #[test]
    fn errors_name_the_file() {
        let err = Rgb8Image::read_png("/nonexistent/x.png").unwrap_err();
        assert!(err.to_string().starts_with("/nonexistent/x.png: cannot open"), "{err}");
        let err = Rgb8Image::decode_png(&b"not a png"[..], Path::new("junk.png")).unwrap_err();
        assert!(err.to_string().starts_with("junk.png: not a readable PNG"), "{err}");
        let bad = Rgb8Image { width: 2, height: 2, data: vec![0; 3] };
        let err = bad.write_png(temp_path("bad.png")).unwrap_err();
        assert!(err.to_string().contains("does not match"), "{err}");
    }

    proptest! {
        #[test]
        fn decoding_random_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let _ = Rgb8Image::decode_png(&bytes[..], Path::new("r.png"));
        }

        #[test]
        fn decoding_mutated_png_never_panics(edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..8),
                                             cut in any::<usize>()) {
            let data: Vec<u8> = (0..4 * 3 * 3).map(|v| v as u8).collect();
            let mut bytes = encode(4, 3, png::ColorType::Rgb, png::BitDepth::Eight, &data);
            for (pos, val) in edits {
                let n = bytes.len();
                bytes[pos % n] = val;
            }
            let keep = cut % (bytes.len() + 1);
            let _ = Rgb8Image::decode_png(&bytes[..keep], Path::new("m.png"));
            let _ = Rgb8Image::decode_png(&bytes[..], Path::new("m.png"));
        }
    }
}
