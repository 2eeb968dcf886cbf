//! Colour maps: a value in a fixed range to an RGB colour.
//!
//! `viridis` (the default: perceptually uniform, readable in grey and by colour-blind
//! readers; matplotlib's, sampled at eleven points and interpolated linearly), `turbo`
//! (a rainbow without jet's false bands: Mikhailov's polynomial fit, Google 2019) and
//! `coolwarm` (Moreland's diverging map, ParaView's default, for signed fields such as
//! stresses around zero).

/// A colour map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Colormap {
    /// Dark blue → green → yellow.
    #[default]
    Viridis,
    /// Rainbow: dark blue → cyan → yellow → dark red.
    Turbo,
    /// Diverging: blue → light grey → red.
    Coolwarm,
}

/// Viridis at 0, 0.1, …, 1.
const VIRIDIS: [[u8; 3]; 11] = [
    [68, 1, 84],
    [72, 36, 117],
    [65, 68, 135],
    [53, 95, 141],
    [42, 120, 142],
    [33, 145, 140],
    [34, 168, 132],
    [68, 191, 112],
    [122, 209, 81],
    [189, 223, 38],
    [253, 231, 37],
];

/// Moreland's cool-to-warm at 0, 0.125, …, 1.
const COOLWARM: [[u8; 3]; 9] = [
    [59, 76, 192],
    [98, 130, 234],
    [141, 176, 254],
    [184, 208, 249],
    [221, 221, 221],
    [245, 196, 173],
    [244, 154, 123],
    [222, 96, 77],
    [180, 4, 38],
];

/// Colour of what has no value (a domain without the field, NaN).
pub const NO_VALUE: [u8; 3] = [190, 190, 190];

fn table(t: f64, samples: &[[u8; 3]]) -> [u8; 3] {
    let x = t * (samples.len() - 1) as f64;
    let k = (x.floor() as usize).min(samples.len() - 2);
    let w = x - k as f64;
    std::array::from_fn(|c| {
        let (a, b) = (f64::from(samples[k][c]), f64::from(samples[k + 1][c]));
        (a + w * (b - a)).round() as u8
    })
}

fn turbo(t: f64) -> [u8; 3] {
    let poly = |c: [f64; 6]| c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))));
    let r = poly([0.13572138, 4.61539260, -42.66032258, 132.13108234, -152.94239396, 59.28637943]);
    let g = poly([0.09140261, 2.19418839, 4.84296658, -14.18503333, 4.27729857, 2.82956604]);
    let b = poly([0.10667330, 12.64194608, -60.58204836, 110.36276771, -89.90310912, 27.34824973]);
    [r, g, b].map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

impl Colormap {
    /// Colour at `t` in [0, 1] (clamped; NaN gives [`NO_VALUE`]).
    pub fn at(self, t: f64) -> [u8; 3] {
        if t.is_nan() {
            return NO_VALUE;
        }
        let t = t.clamp(0.0, 1.0);
        match self {
            Colormap::Viridis => table(t, &VIRIDIS),
            Colormap::Turbo => turbo(t),
            Colormap::Coolwarm => table(t, &COOLWARM),
        }
    }
}

/// A colour map over a value range: `min` maps to the map's start, `max` to its end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColorScale {
    /// The map.
    pub map: Colormap,
    /// Value at the start of the map.
    pub min: f64,
    /// Value at the end of the map (> `min`).
    pub max: f64,
}

impl ColorScale {
    /// The scale over `[min, max]`; an empty or inverted range is widened around its value so
    /// that a uniform field shows the map's middle colour.
    pub fn new(map: Colormap, min: f64, max: f64) -> Self {
        if max > min {
            Self { map, min, max }
        } else {
            let pad = if min == 0.0 { 1.0 } else { 1e-3 * min.abs() };
            Self { map, min: min - pad, max: min + pad }
        }
    }

    /// Colour of `value` (`None` or NaN: [`NO_VALUE`]); values outside the range take the
    /// colour of its nearer end.
    pub fn color(&self, value: Option<f64>) -> [u8; 3] {
        match value {
            Some(v) => self.map.at((v - self.min) / (self.max - self.min)),
            None => NO_VALUE,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_samples_are_the_published_colours() {
        assert_eq!(Colormap::Viridis.at(0.0), [68, 1, 84]);
        assert_eq!(Colormap::Viridis.at(0.5), [33, 145, 140]);
        assert_eq!(Colormap::Viridis.at(1.0), [253, 231, 37]);
        assert_eq!(Colormap::Coolwarm.at(0.5), [221, 221, 221]);
        // turbo (the polynomial fit): blue, green-yellow middle, dark red
        assert_eq!(Colormap::Turbo.at(0.1), [73, 88, 221]);
        assert_eq!(Colormap::Turbo.at(0.5), [150, 250, 80]);
        assert_eq!(Colormap::Turbo.at(1.0), [144, 13, 0]);
        assert_eq!(Colormap::Viridis.at(-3.0), Colormap::Viridis.at(0.0));
        assert_eq!(Colormap::Viridis.at(f64::NAN), NO_VALUE);
    }

    #[test]
    fn scale_maps_its_range_and_widens_a_uniform_one() {
        let s = ColorScale::new(Colormap::Viridis, -2.0, 2.0);
        assert_eq!(s.color(Some(0.0)), Colormap::Viridis.at(0.5));
        assert_eq!(s.color(Some(5.0)), Colormap::Viridis.at(1.0));
        assert_eq!(s.color(None), NO_VALUE);
        let u = ColorScale::new(Colormap::Viridis, 3.0, 3.0);
        assert!(u.min < 3.0 && u.max > 3.0);
        assert_eq!(u.color(Some(3.0)), Colormap::Viridis.at(0.5));
    }
}
