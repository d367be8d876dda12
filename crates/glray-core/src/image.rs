//! RGB images: reading and writing PNG (and binary PPM, as test helpers write), and comparing
//! two images the way apitrace's diff-images does: a pixel differs when one of its channels is
//! off by more than a fuzz (a share of 255), plus PSNR and a red difference image.

use std::path::Path;

/// An 8-bit RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

impl Image {
    /// From rows bottom to top (as GL and OSMesa hold them), 3 or 4 bytes per pixel.
    pub fn from_bottom_up(width: u32, height: u32, pixels: &[u8], bytes_per_pixel: usize) -> Image {
        let row = width as usize * bytes_per_pixel;
        let mut rgb = Vec::with_capacity(width as usize * height as usize * 3);
        for y in (0..height as usize).rev() {
            for p in pixels[y * row..(y + 1) * row].chunks(bytes_per_pixel) {
                rgb.extend_from_slice(&p[..3]);
            }
        }
        Image { width, height, rgb }
    }

    pub fn read(path: &Path) -> Result<Image, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        if bytes.starts_with(b"P6") {
            return read_ppm(&bytes).map_err(|e| format!("{}: {e}", path.display()));
        }
        read_png(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub fn write_png(&self, path: &Path) -> Result<(), String> {
        let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
        let file = std::io::BufWriter::new(std::fs::File::create(path).map_err(|e| err(&e))?);
        let mut enc = png::Encoder::new(file, self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header().and_then(|mut w| w.write_image_data(&self.rgb)).map_err(|e| err(&e))
    }
}

fn read_png(bytes: &[u8]) -> Result<Image, String> {
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
    dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = dec.read_info().map_err(|e| e.to_string())?;
    let size = reader.output_buffer_size().ok_or("PNG too large")?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    let channels = info.color_type.samples();
    let rgb = match channels {
        1 | 2 => buf[..info.buffer_size()].chunks(channels).flat_map(|p| [p[0], p[0], p[0]]).collect(),
        3 | 4 => buf[..info.buffer_size()].chunks(channels).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        n => return Err(format!("unsupported PNG with {n} channels")),
    };
    Ok(Image { width: info.width, height: info.height, rgb })
}

fn read_ppm(bytes: &[u8]) -> Result<Image, String> {
    // P6, width, height, maxval (255), one whitespace byte, then the pixels.
    let mut fields = Vec::new();
    let mut i = 2;
    while fields.len() < 3 {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        let n: u32 = std::str::from_utf8(&bytes[start..i]).ok().and_then(|s| s.parse().ok()).ok_or("bad PPM header")?;
        fields.push(n);
    }
    let (w, h, max) = (fields[0], fields[1], fields[2]);
    if max != 255 {
        return Err(format!("PPM maxval {max}, only 255 is supported"));
    }
    let data = bytes.get(i + 1..).ok_or("truncated PPM")?;
    let n = w as usize * h as usize * 3;
    if data.len() < n {
        return Err("truncated PPM".into());
    }
    Ok(Image { width: w, height: h, rgb: data[..n].to_vec() })
}

/// The outcome of comparing two images.
#[derive(Debug, Clone)]
pub struct Comparison {
    pub pixels: u64,
    /// Pixels with a channel off by more than the fuzz.
    pub differing: u64,
    /// Peak signal-to-noise ratio in dB over all channels (infinite when identical).
    pub psnr: f64,
    /// The same over the pixels of the pictures' objects only: those that are not, in both
    /// images, the colour of the first image's first pixel (the background of a picture whose
    /// corner shows it). A small object on a big background otherwise scores high whatever it
    /// looks like.
    pub psnr_objects: f64,
    pub max_channel_error: u8,
    /// Red where pixels differ, a dimmed grey copy of the first image elsewhere.
    pub diff: Image,
}

impl Comparison {
    pub fn differing_share(&self) -> f64 {
        if self.pixels == 0 {
            0.0
        } else {
            self.differing as f64 / self.pixels as f64
        }
    }
}

/// Compares `a` with `b`; `fuzz` is the share of 255 a channel may be off (0.05 = 12.75).
pub fn compare(a: &Image, b: &Image, fuzz: f64) -> Result<Comparison, String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!("sizes differ: {}x{} and {}x{}", a.width, a.height, b.width, b.height));
    }
    let limit = fuzz * 255.0;
    let mut differing = 0u64;
    let mut sq_sum = 0f64;
    let mut max_err = 0u8;
    let mut diff = Vec::with_capacity(a.rgb.len());
    let background = a.rgb.get(..3).unwrap_or(&[]);
    let (mut object_sq_sum, mut object_samples) = (0f64, 0u64);
    for (pa, pb) in a.rgb.chunks(3).zip(b.rgb.chunks(3)) {
        let mut worst = 0u8;
        let object = pa != background || pb != background;
        for c in 0..3 {
            let e = pa[c].abs_diff(pb[c]);
            worst = worst.max(e);
            sq_sum += (e as f64) * (e as f64);
            if object {
                object_sq_sum += (e as f64) * (e as f64);
                object_samples += 1;
            }
        }
        max_err = max_err.max(worst);
        if worst as f64 > limit {
            differing += 1;
            diff.extend_from_slice(&[255, 0, 0]);
        } else {
            let grey = ((pa[0] as u32 + pa[1] as u32 + pa[2] as u32) / 3 / 3) as u8;
            diff.extend_from_slice(&[grey, grey, grey]);
        }
    }
    let samples = a.rgb.len().max(1) as f64;
    let mse = sq_sum / samples;
    let db = |mse: f64| if mse == 0.0 { f64::INFINITY } else { 10.0 * (255.0f64 * 255.0 / mse).log10() };
    Ok(Comparison {
        pixels: (a.rgb.len() / 3) as u64,
        differing,
        psnr: db(mse),
        psnr_objects: db(object_sq_sum / object_samples.max(1) as f64),
        max_channel_error: max_err,
        diff: Image { width: a.width, height: a.height, rgb: diff },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(px: &[[u8; 3]]) -> Image {
        Image { width: px.len() as u32, height: 1, rgb: px.iter().flatten().copied().collect() }
    }

    #[test]
    fn identical_images_have_no_differences_and_infinite_psnr() {
        let a = img(&[[1, 2, 3], [200, 100, 0]]);
        let c = compare(&a, &a, 0.05).unwrap();
        assert_eq!(c.differing, 0);
        assert!(c.psnr.is_infinite());
    }

    #[test]
    fn the_fuzz_decides_which_pixels_differ() {
        let a = img(&[[100, 100, 100], [100, 100, 100], [0, 0, 0], [9, 9, 9]]);
        let b = img(&[[112, 100, 100], [100, 114, 100], [0, 0, 255], [9, 9, 9]]);
        let c = compare(&a, &b, 0.05).unwrap(); // limit 12.75
        assert_eq!(c.differing, 2);
        assert_eq!(c.max_channel_error, 255);
        assert_eq!(&c.diff.rgb[3..6], &[255, 0, 0]);
        assert_ne!(&c.diff.rgb[0..3], &[255, 0, 0]);
        assert!((c.differing_share() - 0.5).abs() < 1e-12);
        let strict = compare(&a, &b, 0.0).unwrap();
        assert_eq!(strict.differing, 3);
        // PSNR: mse = (144 + 196 + 65025) / 12
        let expect = 10.0 * (255.0f64 * 255.0 / ((144.0 + 196.0 + 65025.0) / 12.0)).log10();
        assert!((c.psnr - expect).abs() < 1e-9);
    }

    #[test]
    fn different_sizes_are_an_error() {
        assert!(compare(&img(&[[0, 0, 0]]), &img(&[[0, 0, 0], [0, 0, 0]]), 0.05).is_err());
    }

    #[test]
    fn png_and_ppm_round_trip() {
        let dir = std::env::temp_dir().join(format!("glray-img-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let a = Image { width: 2, height: 2, rgb: vec![1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12] };
        a.write_png(&dir.join("a.png")).unwrap();
        assert_eq!(Image::read(&dir.join("a.png")).unwrap(), a);
        let mut ppm = b"P6\n2 2\n255\n".to_vec();
        ppm.extend_from_slice(&a.rgb);
        std::fs::write(dir.join("a.ppm"), ppm).unwrap();
        assert_eq!(Image::read(&dir.join("a.ppm")).unwrap(), a);
        std::fs::write(dir.join("bad.ppm"), b"P6\n2 2\n255\n\x01").unwrap();
        assert!(Image::read(&dir.join("bad.ppm")).unwrap_err().contains("truncated"));
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn bottom_up_rows_are_flipped() {
        let px = [1, 1, 1, 9, 2, 2, 2, 9]; // RGBA, 1x2, bottom row first
        let i = Image::from_bottom_up(1, 2, &px, 4);
        assert_eq!(i.rgb, vec![2, 2, 2, 1, 1, 1]);
    }
}
