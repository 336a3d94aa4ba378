//! What a WebSocket stream asks of its frames (a format, PNG, JPEG or
//! WebP; a width to scale them down to, the client's canvas; progressive
//! resolution), asked on the stream's URL
//! (`?format=jpeg&quality=85&width=640&progressive=true`) or by message
//! (`{"stream": {...}}`). The request and its checks are the contract's
//! (`pathstream_wire::stream`, re-exported here); scaling frames down
//! without changing the session's film is here.

pub use pathstream_wire::stream::{StreamFormat, StreamRequest, StreamSettings};

/// `pixels` (w x h, row-major) averaged down to `width` columns and the
/// rows that keep the aspect ratio: each output pixel is the mean of the
/// input pixels whose indices fall in its footprint (in linear radiance,
/// before tone mapping).
pub fn downscale(pixels: &[[f32; 3]], w: u32, h: u32, width: u32) -> (u32, u32, Vec<[f32; 3]>) {
    let width = width.clamp(1, w);
    let height = ((u64::from(h) * u64::from(width)).div_ceil(u64::from(w)) as u32).clamp(1, h);
    let span = |o: u32, out: u32, n: u32| {
        let a = (u64::from(o) * u64::from(n) / u64::from(out)) as usize;
        let b = (u64::from(o + 1) * u64::from(n)).div_ceil(u64::from(out)) as usize;
        a..b.max(a + 1)
    };
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for oy in 0..height {
        let ys = span(oy, height, h);
        for ox in 0..width {
            let xs = span(ox, width, w);
            let mut sum = [0f64; 3];
            for y in ys.clone() {
                for x in xs.clone() {
                    let p = pixels[y * w as usize + x];
                    for c in 0..3 {
                        sum[c] += f64::from(p[c]);
                    }
                }
            }
            let n = (ys.len() * xs.len()) as f64;
            out.push(sum.map(|v| (v / n) as f32));
        }
    }
    (width, height, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downscaling_keeps_the_mean_and_the_aspect() {
        let (w, h) = (10u32, 6u32);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| [i as f32, 1.0, (i % 3) as f32])
            .collect();
        let (dw, dh, small) = downscale(&pixels, w, h, 5);
        assert_eq!((dw, dh), (5, 3));
        // 2x2 blocks: the first is pixels 0, 1, 10, 11.
        assert_eq!(small[0], [5.5, 1.0, (0.0 + 1.0 + 1.0 + 2.0) / 4.0]);
        let mean = |p: &[[f32; 3]]| p.iter().map(|v| f64::from(v[0])).sum::<f64>() / p.len() as f64;
        assert!((mean(&small) - mean(&pixels)).abs() < 1e-9);
        let (_, _, same) = downscale(&pixels, w, h, 10);
        assert_eq!(same, pixels);
        assert_eq!(downscale(&pixels, w, h, 1).0, 1);
    }
}
