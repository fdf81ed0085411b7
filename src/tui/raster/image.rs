//! The encoders' input: an 8-bit RGBA image with straight (not premultiplied) alpha, rows top
//! to bottom, and the nearest-pixel enlargement of a frame drawn at a lower resolution.

/// An RGBA image, 4 bytes a pixel (red, green, blue, alpha; straight alpha), row by row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbaImage {
    width: u32,
    height: u32,
    data: Vec<u8>,
}

impl RgbaImage {
    /// A `width × height` image, every pixel transparent black.
    #[must_use]
    pub fn new(width: u32, height: u32) -> RgbaImage {
        RgbaImage {
            width,
            height,
            data: vec![0; 4 * width as usize * height as usize],
        }
    }

    /// A `width × height` image with the pixel at (x, y) from `f(x, y)`.
    #[must_use]
    pub fn from_fn(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> [u8; 4]) -> RgbaImage {
        let mut data = Vec::with_capacity(4 * width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                data.extend_from_slice(&f(x, y));
            }
        }
        RgbaImage {
            width,
            height,
            data,
        }
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixel at (x, y); panics outside the image.
    #[must_use]
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        assert!(x < self.width && y < self.height, "({x}, {y}) outside");
        let i = 4 * (y as usize * self.width as usize + x as usize);
        [
            self.data[i],
            self.data[i + 1],
            self.data[i + 2],
            self.data[i + 3],
        ]
    }

    /// The bytes, 4 a pixel, row by row.
    #[must_use]
    pub fn as_raw(&self) -> &[u8] {
        &self.data
    }

    /// The bytes, mutable.
    pub fn as_raw_mut(&mut self) -> &mut [u8] {
        &mut self.data
    }

    /// The bytes, taken.
    #[must_use]
    pub fn into_raw(self) -> Vec<u8> {
        self.data
    }

    /// This image enlarged (or shrunk) to `width × height` by taking each pixel's nearest
    /// source pixel: the source column of x is ⌊(x + ½) · w / width⌋ (the pixel whose span
    /// holds the target pixel's centre), rows alike.
    #[must_use]
    pub fn resize_nearest(&self, width: u32, height: u32) -> RgbaImage {
        let column = |x: u32| -> usize {
            let c = (2 * u64::from(x) + 1) * u64::from(self.width) / (2 * u64::from(width));
            c.min(u64::from(self.width.max(1) - 1)) as usize
        };
        let columns: Vec<usize> = (0..width).map(column).collect();
        let mut data = Vec::with_capacity(4 * width as usize * height as usize);
        for y in 0..height {
            let r = (2 * u64::from(y) + 1) * u64::from(self.height) / (2 * u64::from(height));
            let r = r.min(u64::from(self.height.max(1) - 1)) as usize;
            let row = &self.data[4 * r * self.width as usize..][..4 * self.width as usize];
            for &c in &columns {
                data.extend_from_slice(&row[4 * c..4 * c + 4]);
            }
        }
        RgbaImage {
            width,
            height,
            data,
        }
    }
}
