//! Sparse pyramidal Lucas–Kanade (Bouguet 2001): the window around each point of the previous
//! frame is matched in the next frame by Gauss–Newton steps on the intensity difference, first
//! on the coarsest level of an image pyramid and then on each finer one, so motions larger than
//! the window are found coarse and refined fine. The steps use the previous frame's gradients
//! (fixed per window), so each level inverts one 2×2 matrix per point.

use std::ops::Range;

/// A grayscale image, row-major, one f32 per pixel; pixel (x, y) has its centre at index
/// coordinates (x, y).
#[derive(Clone, Copy)]
pub struct GrayImage<'a> {
    /// `width × height` intensities, row after row (in [0, 1] for the default thresholds).
    pub pixels: &'a [f32],
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

/// A 2×2 linear map of window offsets, row-major `[a, b, c, d]`: what lies at offset δ from a
/// point in the image it comes from lies at `[a δx + b δy, c δx + d δy]` from it in the image it
/// is searched in. It carries what a translation cannot: a window that turned, stretched or
/// sheared between the two frames (a limb that swung, a surface that tilted).
pub type Warp = [f32; 4];

/// The warp of a window that only moved.
pub const IDENTITY: Warp = [1.0, 0.0, 0.0, 1.0];

/// Parameters of the tracker; [`Default`] suits images in [0, 1] and motions of a few tens of
/// pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LucasKanade {
    /// Half the side of the square window matched around a point: 7 gives 15×15 pixels.
    pub window_radius: usize,
    /// Pyramid levels including full resolution, each half the previous; fewer where a level
    /// would be smaller than the window. 0 counts as 1.
    pub levels: usize,
    /// The most Gauss–Newton steps per level.
    pub iterations: usize,
    /// The smallest eigenvalue of a window's gradient structure tensor, divided by the window's
    /// pixel count, that counts as texture. Below it at full resolution a point is not followed;
    /// below it on a coarser level that level leaves the guess as it is.
    pub min_eigenvalue: f32,
    /// A step shorter than this (pixels of the level) ends the level's iterations.
    pub epsilon: f32,
}

impl Default for LucasKanade {
    fn default() -> Self {
        Self { window_radius: 7, levels: 4, iterations: 20, min_eigenvalue: 1e-4, epsilon: 0.01 }
    }
}

impl LucasKanade {
    /// Where each point of `prev` (index coordinates) lies in `next`, searched from `guesses`
    /// (where each is expected in `next`; the points themselves when nothing is known), or None
    /// where it cannot be followed: outside the image (the pixels' area, −0.5 to width − 0.5),
    /// non-finite, a window without texture (smallest eigenvalue below `min_eigenvalue` at full
    /// resolution), or not converging inside the image. All None when the images are empty,
    /// differ in size, their pixel counts do not match their sizes, or `guesses` is not one
    /// per point. The same input always gives the same output. The engine follows points with
    /// [`Self::track_consistent`]; the tests check the tracker through this one-way form.
    #[cfg(test)]
    pub fn track(
        &self,
        prev: GrayImage,
        next: GrayImage,
        points: &[[f32; 2]],
        guesses: &[[f32; 2]],
    ) -> Vec<Option<[f32; 2]>> {
        match self.pyramids(prev, next).filter(|_| guesses.len() == points.len()) {
            Some((from, to)) => {
                self.follow_all(&from, &to, points, guesses, &vec![IDENTITY; points.len()])
            }
            None => vec![None; points.len()],
        }
    }

    /// As `track`, keeping only points whose backward track (next -> prev, searched from the
    /// point itself) returns within `max_error` pixels of where they started (forward-backward
    /// check). Both directions use the same pyramids.
    pub fn track_consistent(
        &self,
        prev: GrayImage,
        next: GrayImage,
        points: &[[f32; 2]],
        guesses: &[[f32; 2]],
        max_error: f32,
    ) -> Vec<Option<[f32; 2]>> {
        let warps = vec![IDENTITY; points.len()];
        self.track_warped(prev, next, points, guesses, &warps, max_error)
    }

    /// As [`Self::track_consistent`], with each point's window mapped by its warp from `prev`
    /// to `next` (and back by the inverse), so only the translation is searched. A point whose
    /// warp is singular or not finite is None; all None when `warps` is not one per point.
    pub fn track_warped(
        &self,
        prev: GrayImage,
        next: GrayImage,
        points: &[[f32; 2]],
        guesses: &[[f32; 2]],
        warps: &[Warp],
        max_error: f32,
    ) -> Vec<Option<[f32; 2]>> {
        let one_each = guesses.len() == points.len() && warps.len() == points.len();
        let Some((from, to)) = self.pyramids(prev, next).filter(|_| one_each) else {
            return vec![None; points.len()];
        };
        let inverses: Vec<Warp> = warps.iter().map(|&w| inverse(w)).collect();
        let forward = self.follow_all(&from, &to, points, guesses, warps);
        // A point lost forward goes back as NaN, which is never followed.
        let reached: Vec<[f32; 2]> = forward.iter().map(|p| p.unwrap_or([f32::NAN; 2])).collect();
        let backward = self.follow_all(&to, &from, &reached, points, &inverses);
        let returns = |start: &[f32; 2], back: Option<[f32; 2]>| {
            back.is_some_and(|b| (b[0] - start[0]).hypot(b[1] - start[1]) <= max_error)
        };
        (forward.into_iter().zip(backward).zip(points))
            .map(|((there, back), start)| there.filter(|_| returns(start, back)))
            .collect()
    }

    /// The pyramids of both images, or None when they cannot be tracked between.
    fn pyramids(&self, prev: GrayImage, next: GrayImage) -> Option<(Vec<Level>, Vec<Level>)> {
        let valid = |image: &GrayImage| {
            image.width > 0
                && image.height > 0
                && image.width.checked_mul(image.height) == Some(image.pixels.len())
        };
        let same_size = prev.width == next.width && prev.height == next.height;
        if !(valid(&prev) && valid(&next) && same_size) {
            return None;
        }
        let side = window_side(self.window_radius);
        Some((pyramid(prev, self.levels, side), pyramid(next, self.levels, side)))
    }

    /// Every point from `from` to `to`, each searched from its guess with its warp, with one
    /// set of scratch windows for all.
    fn follow_all(
        &self,
        from: &[Level],
        to: &[Level],
        points: &[[f32; 2]],
        guesses: &[[f32; 2]],
        warps: &[Warp],
    ) -> Vec<Option<[f32; 2]>> {
        let side = window_side(self.window_radius);
        let (mut fine, mut coarse) = (Template::new(side), Template::new(side));
        let mut scratch = (&mut fine, &mut coarse);
        (points.iter().zip(guesses).zip(warps))
            .map(|((&p, &g), &w)| self.follow(from, to, [p, g], w, &mut scratch))
            .collect()
    }

    /// One point through the pyramids from where it is guessed to be, coarse to fine, its
    /// window mapped by `warp`; the templates are scratch.
    fn follow(
        &self,
        from: &[Level],
        to: &[Level],
        [point, expected]: [[f32; 2]; 2],
        warp: Warp,
        (fine, coarse): &mut (&mut Template, &mut Template),
    ) -> Option<[f32; 2]> {
        // The template is `from` seen through the warp: where `to`'s window pixel ε looks.
        let unwarp = inverse(warp);
        if !from[0].contains(point) || unwarp.iter().any(|m| !m.is_finite()) {
            return None;
        }
        // Texture is judged at full resolution first, so a flat window costs no coarse work.
        fine.load(&from[0], point, unwarp);
        if !fine.is_textured(self.min_eigenvalue) {
            return None;
        }
        // The guess's offset in the coarsest level's pixels.
        let coarsest = 0.5f32.powi(from.len() as i32 - 1);
        let mut guess = [(expected[0] - point[0]) * coarsest, (expected[1] - point[1]) * coarsest];
        if !(guess[0].is_finite() && guess[1].is_finite()) {
            return None;
        }
        for level in (1..from.len()).rev() {
            let scale = 0.5f32.powi(level as i32);
            let at = [point[0] * scale, point[1] * scale];
            coarse.load(&from[level], at, unwarp);
            if coarse.is_textured(self.min_eigenvalue) {
                guess = self.refine(coarse, &to[level], at, guess)?.0;
            }
            guess = [guess[0] * 2.0, guess[1] * 2.0];
        }
        let (offset, converged) = self.refine(fine, &to[0], point, guess)?;
        let found = [point[0] + offset[0], point[1] + offset[1]];
        (converged && to[0].contains(found)).then_some(found)
    }

    /// Gauss–Newton on one level from `guess`: the offset of `template` (taken at `at`) in
    /// `image`, and whether the last step was shorter than epsilon. None when the window's centre
    /// leaves the image or a step is not finite.
    fn refine(
        &self,
        template: &mut Template,
        image: &Level,
        at: [f32; 2],
        guess: [f32; 2],
    ) -> Option<([f32; 2], bool)> {
        let inverse = template.inverse_tensor();
        let (mut offset, mut last_step) = (guess, [0.0f32; 2]);
        let short = |v: [f32; 2]| v[0] * v[0] + v[1] * v[1] < self.epsilon * self.epsilon;
        for _ in 0..self.iterations {
            let centre = [at[0] + offset[0], at[1] + offset[1]];
            if !image.contains(centre) {
                return None;
            }
            let b = template.mismatch(image, centre);
            let step = [
                (inverse[0] * b[0] + inverse[1] * b[1]) as f32,
                (inverse[1] * b[0] + inverse[2] * b[1]) as f32,
            ];
            if !(step[0].is_finite() && step[1].is_finite()) {
                return None;
            }
            offset = [offset[0] + step[0], offset[1] + step[1]];
            if short(step) {
                return Some((offset, true));
            }
            // Bouncing between two positions: the answer lies halfway.
            if short([step[0] + last_step[0], step[1] + last_step[1]]) {
                return Some(([offset[0] - step[0] / 2.0, offset[1] - step[1] / 2.0], true));
            }
            last_step = step;
        }
        Some((offset, false))
    }
}

/// The luma (0.299 R + 0.587 G + 0.114 B) of rgba pixels, one value per pixel; alpha is ignored.
pub fn luma(rgba: &[[f32; 4]]) -> Vec<f32> {
    rgba.iter().map(|p| 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]).collect()
}

fn window_side(radius: usize) -> usize {
    radius.saturating_mul(2).saturating_add(1)
}

/// The inverse of a warp; not finite where it is singular.
fn inverse([a, b, c, d]: Warp) -> Warp {
    let det = a * d - b * c;
    [d / det, -b / det, -c / det, a / det]
}

/// One pyramid level: intensities and their central-difference gradients, row-major, and
/// the full-resolution pixels' area in this level's coordinates as (left, top, right, bottom).
/// Decimation keeps even pixels, so on coarse levels that area reaches up to half a pixel past
/// the level's own pixels on the right and at the bottom.
struct Level {
    pixels: Vec<f32>,
    gradient_x: Vec<f32>,
    gradient_y: Vec<f32>,
    width: usize,
    height: usize,
    area: [f32; 4],
}

impl Level {
    fn new(pixels: Vec<f32>, width: usize, height: usize, area: [f32; 4]) -> Self {
        let (gradient_x, gradient_y) = gradients(&pixels, width, height);
        Self { pixels, gradient_x, gradient_y, width, height, area }
    }

    /// Whether `p` is finite and inside the image's area.
    fn contains(&self, p: [f32; 2]) -> bool {
        let [left, top, right, bottom] = self.area;
        (left..=right).contains(&p[0]) && (top..=bottom).contains(&p[1])
    }

    /// The bilinear samples of the intensity and both gradients at `p`, None unless all four
    /// taps are pixels of the level.
    fn bilinear(&self, p: [f32; 2]) -> Option<[f32; 3]> {
        let (x, y) = (p[0].floor(), p[1].floor());
        let inside = x >= 0.0 && y >= 0.0 && x + 1.0 < self.width as f32;
        if !(inside && y + 1.0 < self.height as f32) {
            return None;
        }
        let (tx, ty) = (p[0] - x, p[1] - y);
        let at = y as usize * self.width + x as usize;
        let taps = [at, at + 1, at + self.width, at + self.width + 1];
        let weights = [(1.0 - tx) * (1.0 - ty), tx * (1.0 - ty), (1.0 - tx) * ty, tx * ty];
        let sample = |map: &[f32]| taps.iter().zip(weights).map(|(&i, w)| w * map[i]).sum();
        Some([sample(&self.pixels), sample(&self.gradient_x), sample(&self.gradient_y)])
    }
}

/// `image` and up to `levels − 1` halvings of it, stopping before one narrower than `side`.
fn pyramid(image: GrayImage, levels: usize, side: usize) -> Vec<Level> {
    let (right, bottom) = (image.width as f32 - 0.5, image.height as f32 - 0.5);
    let area = |scale: f32| [-0.5 * scale, -0.5 * scale, right * scale, bottom * scale];
    let mut pyramid = vec![Level::new(image.pixels.to_vec(), image.width, image.height, area(1.0))];
    while pyramid.len() < levels {
        let last = &pyramid[pyramid.len() - 1];
        let (width, height) = (last.width.div_ceil(2), last.height.div_ceil(2));
        if width < side || height < side {
            break;
        }
        let scale = 0.5f32.powi(pyramid.len() as i32);
        pyramid.push(Level::new(downsample(last, width), width, height, area(scale)));
    }
    pyramid
}

/// `level` blurred by the binomial filter [1 4 6 4 1]/16 (borders repeated) with every other
/// pixel kept: pixel (x, y) of the result is centred on (2x, 2y) of `level`, so a point's
/// coordinates halve from one level to the next.
fn downsample(level: &Level, width: usize) -> Vec<f32> {
    let (w, h) = (level.width, level.height);
    let mut rows = Vec::with_capacity(width * h);
    for row in level.pixels.chunks_exact(w) {
        rows.extend((0..width).map(|x| binomial(2 * x, w, |i| row[i])));
    }
    let height = h.div_ceil(2);
    let mut out = Vec::with_capacity(width * height);
    for y in 0..height {
        out.extend((0..width).map(|x| binomial(2 * y, h, |i| rows[i * width + x])));
    }
    out
}

/// The binomial filter of `sample` at `at` on a line of `len` samples, the ends repeated.
fn binomial(at: usize, len: usize, sample: impl Fn(usize) -> f32) -> f32 {
    const TAPS: [f32; 5] = [1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0];
    let index = |k: usize| (at + k).saturating_sub(2).min(len - 1);
    TAPS.iter().enumerate().map(|(k, tap)| tap * sample(index(k))).sum()
}

/// Central differences in x and y (one-sided at the borders, zero across a single pixel).
fn gradients(pixels: &[f32], width: usize, height: usize) -> (Vec<f32>, Vec<f32>) {
    let at = |x: usize, y: usize| pixels[y * width + x];
    let neighbours = |i: usize, len: usize| (i.saturating_sub(1), (i + 1).min(len - 1));
    let (mut gradient_x, mut gradient_y) = (Vec::new(), Vec::new());
    for y in 0..height {
        let (up, down) = neighbours(y, height);
        for x in 0..width {
            let (left, right) = neighbours(x, width);
            gradient_x.push((at(right, y) - at(left, y)) / (right - left).max(1) as f32);
            gradient_y.push((at(x, down) - at(x, up)) / (down - up).max(1) as f32);
        }
    }
    (gradient_x, gradient_y)
}

/// Where a window's bilinear samples come from. Window pixel (i, j) is sampled from image
/// pixels (left + i, top + j) to (left + i + 1, top + j + 1), with the same weights for every
/// pixel because the window's offsets are whole pixels. It counts only where all four lie in
/// the image (i in `columns`, j in `rows`): beyond the border a clamped image would not move
/// with the scene and would pull windows near the edge, as every window on a coarse level is.
#[derive(Default)]
struct Footprint {
    left: i64,
    top: i64,
    weights: [f32; 4],
    columns: Range<usize>,
    rows: Range<usize>,
}

impl Footprint {
    fn new(level: &Level, centre: [f32; 2], side: usize) -> Self {
        let (x, y) = (centre[0].floor(), centre[1].floor());
        let (tx, ty) = (centre[0] - x, centre[1] - y);
        let weights = [(1.0 - tx) * (1.0 - ty), tx * (1.0 - ty), (1.0 - tx) * ty, tx * ty];
        let radius = (side / 2) as i64;
        let (left, top) = ((x as i64).saturating_sub(radius), (y as i64).saturating_sub(radius));
        // The offsets k with start + k in [0, len − 2], so both taps are pixels.
        let span = |start: i64, len: usize| {
            let low = start.saturating_neg().clamp(0, side as i64);
            let high = (len as i64 - 1).saturating_sub(start).clamp(low, side as i64);
            low as usize..high as usize
        };
        let (columns, rows) = (span(left, level.width), span(top, level.height));
        Self { left, top, weights, columns, rows }
    }

    /// The bilinear samples of `values` (one of `level`'s maps) along window row `row` over
    /// `columns`, which must lie in the footprint's rows and columns.
    fn samples<'a>(
        &self,
        values: &'a [f32],
        width: usize,
        row: usize,
        columns: &Range<usize>,
    ) -> impl Iterator<Item = f32> + 'a {
        let (x, y) = (self.left + columns.start as i64, self.top + row as i64);
        let start = y as usize * width + x as usize;
        let len = columns.len() + 1;
        let upper = &values[start..start + len];
        let lower = &values[start + width..start + width + len];
        let w = self.weights;
        let pairs = upper.iter().zip(&upper[1..]).zip(lower.iter().zip(&lower[1..]));
        pairs.map(move |((u0, u1), (l0, l1))| w[0] * u0 + w[1] * u1 + w[2] * l0 + w[3] * l1)
    }
}

fn intersect(a: &Range<usize>, b: &Range<usize>) -> Range<usize> {
    let start = a.start.max(b.start);
    start..a.end.min(b.end).max(start)
}

/// Σ a·b in eight interleaved partial sums, so the additions need not wait on each other.
fn dot(a: &[f32], b: &[f32]) -> f32 {
    let (a8, b8) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f32 = a8.remainder().iter().zip(b8.remainder()).map(|(x, y)| x * y).sum();
    let mut lanes = [0.0f32; 8];
    for (x, y) in a8.zip(b8) {
        for k in 0..8 {
            lanes[k] += x[k] * y[k];
        }
    }
    lanes.iter().sum::<f32>() + tail
}

/// A window of the previous frame: its intensities and gradients (`side × side`, row-major;
/// gradients zero outside its footprint, so those pixels weigh nothing) and structure tensor
/// Σ ∇I ∇Iᵀ as (xx, xy, yy).
struct Template {
    side: usize,
    footprint: Footprint,
    values: Vec<f32>,
    gradient_x: Vec<f32>,
    gradient_y: Vec<f32>,
    tensor: [f32; 3],
    /// Scratch for `mismatch`: T − J per window pixel.
    differences: Vec<f32>,
}

impl Template {
    fn new(side: usize) -> Self {
        let zeros = vec![0.0; side * side];
        let (values, gradient_x, gradient_y) = (zeros.clone(), zeros.clone(), zeros.clone());
        let footprint = Footprint::default();
        Self {
            side,
            footprint,
            values,
            gradient_x,
            gradient_y,
            tensor: [0.0; 3],
            differences: zeros,
        }
    }

    /// The window of `level` around `centre`, each window offset ε sampled at
    /// `centre + unwarp·ε`: the image seen through the inverse of the point's warp.
    fn load(&mut self, level: &Level, centre: [f32; 2], unwarp: Warp) {
        if unwarp == IDENTITY {
            self.load_shifted(level, centre);
        } else {
            self.load_warped(level, centre, unwarp);
        }
        let (gx, gy) = (&self.gradient_x, &self.gradient_y);
        self.tensor = [dot(gx, gx), dot(gx, gy), dot(gy, gy)];
    }

    /// The window's pixels share one set of bilinear weights: rows of the maps are read whole.
    fn load_shifted(&mut self, level: &Level, centre: [f32; 2]) {
        let footprint = Footprint::new(level, centre, self.side);
        self.gradient_x.fill(0.0);
        self.gradient_y.fill(0.0);
        let columns = &footprint.columns;
        for row in footprint.rows.clone().filter(|_| !columns.is_empty()) {
            let at = row * self.side + columns.start..row * self.side + columns.end;
            let maps = [
                (&mut self.values, &level.pixels),
                (&mut self.gradient_x, &level.gradient_x),
                (&mut self.gradient_y, &level.gradient_y),
            ];
            for (window, map) in maps {
                let samples = footprint.samples(map, level.width, row, columns);
                window[at.clone()].iter_mut().zip(samples).for_each(|(v, s)| *v = s);
            }
        }
        self.footprint = footprint;
    }

    /// Each window pixel sampled on its own; the gradients are turned into the window's
    /// coordinates (∇ε = unwarpᵀ ∇I), and a pixel whose sample leaves the level weighs nothing.
    fn load_warped(&mut self, level: &Level, centre: [f32; 2], [a, b, c, d]: Warp) {
        let radius = (self.side / 2) as f32;
        for k in 0..self.side * self.side {
            let e = [(k % self.side) as f32 - radius, (k / self.side) as f32 - radius];
            let p = [centre[0] + a * e[0] + b * e[1], centre[1] + c * e[0] + d * e[1]];
            let [value, gx, gy] = level.bilinear(p).unwrap_or([0.0; 3]);
            self.values[k] = value;
            self.gradient_x[k] = a * gx + c * gy;
            self.gradient_y[k] = b * gx + d * gy;
        }
        let whole = 0..self.side;
        self.footprint = Footprint { columns: whole.clone(), rows: whole, ..Footprint::default() };
    }

    /// Whether the tensor's smallest eigenvalue per window pixel reaches `min_eigenvalue`
    /// (false for NaN).
    fn is_textured(&self, min_eigenvalue: f32) -> bool {
        let [xx, xy, yy] = self.tensor.map(f64::from);
        let smallest = (xx + yy - ((xx - yy).powi(2) + 4.0 * xy * xy).sqrt()) / 2.0;
        smallest / self.values.len() as f64 >= f64::from(min_eigenvalue)
    }

    /// The tensor's inverse as (xx, xy, yy); infinite or NaN when singular, which `refine`
    /// turns into a lost point.
    fn inverse_tensor(&self) -> [f64; 3] {
        let [xx, xy, yy] = self.tensor.map(f64::from);
        let det = xx * yy - xy * xy;
        [yy / det, -xy / det, xx / det]
    }

    /// Σ (T − J) ∇T over the window pixels inside both images, with J the window of `image`
    /// centred on `centre`: the right-hand side of the Gauss–Newton step.
    fn mismatch(&mut self, image: &Level, centre: [f32; 2]) -> [f64; 2] {
        let target = Footprint::new(image, centre, self.side);
        let columns = intersect(&self.footprint.columns, &target.columns);
        let rows = intersect(&self.footprint.rows, &target.rows);
        self.differences.fill(0.0);
        for row in rows.filter(|_| !columns.is_empty()) {
            let at = row * self.side + columns.start..row * self.side + columns.end;
            let samples = target.samples(&image.pixels, image.width, row, &columns);
            let pairs = self.differences[at.clone()].iter_mut().zip(&self.values[at]);
            pairs.zip(samples).for_each(|((d, value), sample)| *d = value - sample);
        }
        let d = &self.differences;
        [dot(d, &self.gradient_x), dot(d, &self.gradient_y)].map(f64::from)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The square [ORIGIN, ORIGIN + SPAN)² the test texture covers.
    const ORIGIN: f64 = -64.0;
    const SPAN: f64 = 384.0;

    /// A blurred pseudo-random field with detail at every scale, as photographs have (a field
    /// with fine detail only leaves coarse levels without texture), and analytic so a shifted
    /// copy is exact: for σ of 2, 4, 8 and 16 pixels, a Gaussian bump of random height in
    /// [−1, 1] at a random spot in every 2σ-wide cell of a grid, all summed and squashed
    /// smoothly into [0, 1].
    struct Texture {
        scales: Vec<(f64, Vec<[f64; 3]>)>,
    }

    impl Texture {
        fn new(seed: u64) -> Self {
            let mut rng = SplitMix64::new(seed);
            let mut bumps = |sigma: f64| {
                let (cell, n) = (2.0 * sigma, (SPAN / (2.0 * sigma)) as usize);
                let mut bumps = Vec::with_capacity(n * n);
                for i in 0..n * n {
                    let (x, y) = ((i % n) as f64 + rng.next_f64(), (i / n) as f64 + rng.next_f64());
                    bumps.push([ORIGIN + x * cell, ORIGIN + y * cell, 2.0 * rng.next_f64() - 1.0]);
                }
                bumps
            };
            Self { scales: [2.0, 4.0, 8.0, 16.0].map(|sigma| (sigma, bumps(sigma))).into() }
        }

        fn at(&self, x: f64, y: f64) -> f32 {
            let mut sum = 0.0;
            for (sigma, bumps) in &self.scales {
                let (cell, n) = (2.0 * sigma, (SPAN / (2.0 * sigma)) as i64);
                let (column, row) = (((x - ORIGIN) / cell) as i64, ((y - ORIGIN) / cell) as i64);
                // Bumps three cells away are 4σ away at least: they add less than e⁻⁸.
                for j in (row - 2).max(0)..(row + 3).min(n) {
                    for i in (column - 2).max(0)..(column + 3).min(n) {
                        let [bx, by, height] = bumps[(j * n + i) as usize];
                        let squared = (x - bx).powi(2) + (y - by).powi(2);
                        sum += height * (-squared / (2.0 * sigma * sigma)).exp();
                    }
                }
            }
            (0.5 + 0.5 * (sum / 2.0).tanh()) as f32
        }

        /// The texture moved by `shift`: pixel (x, y) shows what was at (x, y) − shift.
        fn image(&self, width: usize, height: usize, shift: [f64; 2]) -> Vec<f32> {
            let pixel = |i: usize| ((i % width) as f64 - shift[0], (i / width) as f64 - shift[1]);
            (0..width * height).map(pixel).map(|(x, y)| self.at(x, y)).collect()
        }
    }

    fn gray(pixels: &[f32], width: usize, height: usize) -> GrayImage<'_> {
        GrayImage { pixels, width, height }
    }

    /// Points every `step` pixels, at least `margin` from the border.
    fn grid(width: usize, height: usize, margin: usize, step: usize) -> Vec<[f32; 2]> {
        let ys = (margin..height - margin).step_by(step);
        ys.flat_map(|y| (margin..width - margin).step_by(step).map(move |x| [x as f32, y as f32]))
            .collect()
    }

    /// For each followed point, its distance from where `shift` moved it.
    fn errors(points: &[[f32; 2]], found: &[Option<[f32; 2]>], shift: [f64; 2]) -> Vec<f32> {
        let error = |p: &[f32; 2], f: [f32; 2]| {
            (f[0] - p[0] - shift[0] as f32).hypot(f[1] - p[1] - shift[1] as f32)
        };
        points.iter().zip(found).filter_map(|(p, f)| f.map(|f| error(p, f))).collect()
    }

    /// Asserts that nearly all points were followed (windows with too little texture are not)
    /// and every followed one to within 0.05 px of where `shift` moved it.
    fn assert_recovered(points: &[[f32; 2]], found: &[Option<[f32; 2]>], shift: [f64; 2]) {
        let errors = errors(points, found, shift);
        assert!(errors.len() * 100 >= points.len() * 95, "{} of {}", errors.len(), points.len());
        let worst = errors.iter().copied().fold(0.0, f32::max);
        assert!(worst < 0.05, "{worst} px");
    }

    #[test]
    fn recovers_a_subpixel_translation() {
        let (w, h, shift) = (96, 96, [6.3, -4.7]);
        let texture = Texture::new(1);
        let (prev, next) = (texture.image(w, h, [0.0; 2]), texture.image(w, h, shift));
        let points = grid(w, h, 16, 6);
        let found =
            LucasKanade::default().track(gray(&prev, w, h), gray(&next, w, h), &points, &points);
        assert_recovered(&points, &found, shift);
    }

    #[test]
    fn the_pyramid_recovers_a_large_motion() {
        let (w, h, shift) = (128, 128, [18.0, -14.5]);
        let texture = Texture::new(2);
        let (prev, next) = (texture.image(w, h, [0.0; 2]), texture.image(w, h, shift));
        let (prev, next) = (gray(&prev, w, h), gray(&next, w, h));
        let points = grid(w, h, 28, 6);
        let pyramidal = LucasKanade::default();
        assert_recovered(&points, &pyramidal.track(prev, next, &points, &points), shift);
        // The motion is three window radii: one level alone finds it only by luck.
        let single = LucasKanade { levels: 1, ..pyramidal }.track(prev, next, &points, &points);
        let recovered = errors(&points, &single, shift).iter().filter(|&&e| e < 0.05).count();
        assert!(recovered * 4 < points.len(), "{recovered} of {}", points.len());
    }

    #[test]
    fn a_guess_puts_a_motion_beyond_the_pyramid_in_reach() {
        let (w, h, shift) = (128, 128, [34.0, -27.5]);
        let texture = Texture::new(3);
        let (prev, next) = (texture.image(w, h, [0.0; 2]), texture.image(w, h, shift));
        let (prev, next) = (gray(&prev, w, h), gray(&next, w, h));
        let points = grid(w, h, 40, 6);
        // Two levels reach about two window radii: the motion is well past them.
        let tracker = LucasKanade { levels: 2, ..LucasKanade::default() };
        let blind = tracker.track(prev, next, &points, &points);
        let recovered = errors(&points, &blind, shift).iter().filter(|&&e| e < 0.05).count();
        assert!(recovered * 4 < points.len(), "{recovered} of {}", points.len());
        // A guess three pixels off, as a predicted pose gives, is refined to the motion.
        let guesses: Vec<[f32; 2]> = points
            .iter()
            .map(|p| [p[0] + shift[0] as f32 - 3.0, p[1] + shift[1] as f32 + 2.0])
            .collect();
        let checked = tracker.track_consistent(prev, next, &points, &guesses, 0.1);
        assert_recovered(&points, &checked, shift);
        // A non-finite guess is not followed.
        assert_eq!(tracker.track(prev, next, &points[..1], &[[f32::NAN, 0.0]]), vec![None]);
        // Guesses must be one per point.
        assert_eq!(tracker.track(prev, next, &points[..2], &points[..1]), vec![None; 2]);
    }

    #[test]
    fn a_warp_follows_a_window_that_turned_and_stretched() {
        let (w, h, centre, shift) = (128, 128, [64.0f64, 64.0], [3.4f64, -2.6]);
        // Turned 30 degrees and stretched by a fifth about the centre, then moved.
        let (angle, scale) = (30f64.to_radians(), 1.2);
        let warp = [angle.cos(), -angle.sin(), angle.sin(), angle.cos()].map(|m| scale * m);
        let texture = Texture::new(7);
        let prev = texture.image(w, h, [0.0; 2]);
        // Pixel q of `next` shows what was at warp⁻¹ (q − centre − shift) + centre.
        let det = warp[0] * warp[3] - warp[1] * warp[2];
        let next: Vec<f32> = (0..w * h)
            .map(|i| {
                let q =
                    [(i % w) as f64 - centre[0] - shift[0], (i / w) as f64 - centre[1] - shift[1]];
                let x = (warp[3] * q[0] - warp[1] * q[1]) / det + centre[0];
                let y = (warp[0] * q[1] - warp[2] * q[0]) / det + centre[1];
                texture.at(x, y)
            })
            .collect();
        let moved = |p: &[f32; 2]| {
            let d = [p[0] as f64 - centre[0], p[1] as f64 - centre[1]];
            let x = warp[0] * d[0] + warp[1] * d[1] + centre[0] + shift[0];
            let y = warp[2] * d[0] + warp[3] * d[1] + centre[1] + shift[1];
            [x as f32, y as f32]
        };
        let (prev, next) = (gray(&prev, w, h), gray(&next, w, h));
        let points: Vec<[f32; 2]> = grid(w, h, 40, 4);
        let guesses: Vec<[f32; 2]> = points.iter().map(moved).collect();
        let tracker = LucasKanade::default();
        let within = |found: &[Option<[f32; 2]>], tolerance: f32| {
            let hit = |(g, f): (&[f32; 2], &Option<[f32; 2]>)| {
                f.is_some_and(|f| (f[0] - g[0]).hypot(f[1] - g[1]) < tolerance)
            };
            guesses.iter().zip(found).filter(|&pair| hit(pair)).count()
        };
        // Searched from the right place, a window matched as it was is still off.
        let plain = tracker.track_consistent(prev, next, &points, &guesses, 1.0);
        assert!(
            within(&plain, 0.05) * 2 < points.len(),
            "{} of {}",
            within(&plain, 0.05),
            points.len()
        );
        let warps = vec![warp.map(|m| m as f32); points.len()];
        let warped = tracker.track_warped(prev, next, &points, &guesses, &warps, 0.1);
        assert!(
            within(&warped, 0.05) * 100 >= points.len() * 95,
            "{} of {}",
            within(&warped, 0.05),
            points.len()
        );
        // A singular warp follows nothing; warps must be one per point.
        let flat = vec![[1.0, 2.0, 0.5, 1.0]; points.len()];
        assert!(tracker
            .track_warped(prev, next, &points, &guesses, &flat, 1.0)
            .iter()
            .all(Option::is_none));
        assert_eq!(
            tracker.track_warped(prev, next, &points, &guesses, &warps[1..], 1.0),
            vec![None; points.len()]
        );
        // The identity is the plain tracker.
        let identity = vec![IDENTITY; points.len()];
        assert_eq!(tracker.track_warped(prev, next, &points, &guesses, &identity, 1.0), plain);
    }

    #[test]
    fn unfollowable_points_and_images_give_none() {
        let tracker = LucasKanade::default();
        let flat = vec![0.5; 64 * 64];
        let flat = gray(&flat, 64, 64);
        let points = grid(64, 64, 0, 5);
        assert!(tracker.track(flat, flat, &points, &points).iter().all(Option::is_none));
        let broken = vec![f32::NAN; 64 * 64];
        let broken = gray(&broken, 64, 64);
        assert!(tracker.track(broken, broken, &points, &points).iter().all(Option::is_none));

        let texture = Texture::new(3).image(64, 64, [0.0; 2]);
        let image = gray(&texture, 64, 64);
        let outside = [[-1.0, 10.0], [10.0, 63.6], [f32::NAN, 5.0], [5.0, f32::INFINITY]];
        assert_eq!(tracker.track(image, image, &outside, &outside), vec![None; 4]);
        assert_eq!(
            tracker.track(image, image, &[[32.0, 32.0]], &[[32.0, 32.0]]),
            vec![Some([32.0, 32.0])]
        );
        assert!(tracker.track(image, image, &[], &[]).is_empty());
        assert!(tracker.track_consistent(image, image, &[], &[], 1.0).is_empty());

        let tiny = [0.25];
        for (a, b) in [(gray(&[], 0, 0), gray(&[], 0, 0)), (gray(&tiny, 1, 1), gray(&tiny, 1, 1))] {
            assert_eq!(
                tracker.track(a, b, &[[0.0, 0.0], [0.5, 0.5]], &[[0.0, 0.0], [0.5, 0.5]]),
                vec![None; 2]
            );
            assert_eq!(
                tracker.track_consistent(a, b, &[[0.0, 0.0]], &[[0.0, 0.0]], 1.0),
                vec![None]
            );
        }
        let mismatched = [gray(&texture, 32, 128), gray(&texture, 64, 63), gray(&tiny, 64, 64)];
        for other in mismatched {
            assert_eq!(tracker.track(image, other, &[[32.0, 32.0]], &[[32.0, 32.0]]), vec![None]);
        }
    }

    #[test]
    fn the_forward_backward_check_drops_an_occluded_point() {
        let (w, h, shift) = (96, 96, [2.4, 1.3]);
        let texture = Texture::new(4);
        let prev = texture.image(w, h, [0.0; 2]);
        let mut next = texture.image(w, h, shift);
        // Something else in front of where the occluded point went.
        let (occluded, patch) = ([48.0f32, 48.0], Texture::new(5));
        for y in 40..58 {
            for x in 40..58 {
                next[y * w + x] = patch.at(x as f64, y as f64);
            }
        }
        let (prev, next) = (gray(&prev, w, h), gray(&next, w, h));
        let points = grid(w, h, 12, 6);
        let tracker = LucasKanade::default();
        let plain = tracker.track(prev, next, &points, &points);
        let checked = tracker.track_consistent(prev, next, &points, &points, 0.1);
        let at = points.iter().position(|&p| p == occluded).unwrap();
        assert!(plain[at].is_some(), "only the check should drop it");
        assert_eq!(checked[at], None);
        // Points whose windows stay clear of the patch are kept, unchanged.
        let clear = |p: &[f32; 2]| p.iter().any(|&c| !(30.0..=66.0).contains(&c));
        for ((p, checked), plain) in points.iter().zip(&checked).zip(&plain) {
            if clear(p) {
                assert!(checked.is_some() && checked == plain, "{p:?}: {checked:?} {plain:?}");
            }
        }
    }

    #[test]
    fn luma_weights_the_channels() {
        let values = luma(&[[1.0; 4], [0.0, 1.0, 0.0, 1.0]]);
        assert!((values[0] - 1.0).abs() < 1e-6, "{values:?}");
        assert!((values[1] - 0.587).abs() < 1e-7, "{values:?}");
    }

    /// About 6000 points between 256×256 frames, the load per camera and frame; prints the time
    /// (meaningful with --release --nocapture).
    #[test]
    fn tracks_thousands_of_points() {
        let (w, h, shift) = (256, 256, [3.6, -2.2]);
        let texture = Texture::new(6);
        let (prev, next) = (texture.image(w, h, [0.0; 2]), texture.image(w, h, shift));
        let points = grid(w, h, 12, 3);
        assert!(points.len() >= 6000, "{}", points.len());
        let start = std::time::Instant::now();
        let found =
            LucasKanade::default().track(gray(&prev, w, h), gray(&next, w, h), &points, &points);
        println!("{} points tracked in {:?}", points.len(), start.elapsed());
        let recovered = errors(&points, &found, shift).iter().filter(|&&e| e < 0.05).count();
        assert!(recovered * 100 >= points.len() * 99, "{recovered} of {}", points.len());
    }
}
