//! The one colour of each vehicle in every output that draws one (the report's plots, the replay
//! page): survey AUV k in colour k of the Okabe–Ito palette (Okabe and Ito, "Color Universal
//! Design", 2008), chosen to stay distinct under the common colour-vision deficiencies, with its
//! yellow, which is near invisible as a line on white, replaced by two darker colours of Paul
//! Tol's "muted" scheme (wine and olive); the CNA in black. Beyond eight AUVs the colours repeat.
//! Beside them: a grey for reference lines and a colour-blind-safe sequential scale (viridis) for
//! heat maps.

/// An sRGB colour.
pub type Rgb = (u8, u8, u8);

/// The survey AUVs' colours, by index: blue, vermillion, bluish green, reddish purple, sky blue,
/// orange, wine, olive.
pub const VEHICLES: [Rgb; 8] = [
    (0, 114, 178),
    (213, 94, 0),
    (0, 158, 115),
    (204, 121, 167),
    (86, 180, 233),
    (230, 159, 0),
    (136, 34, 85),
    (153, 153, 51),
];

/// The CNA's colour.
pub const CNA: Rgb = (0, 0, 0);

/// Reference lines that are not a vehicle (limits, bounds, a zone's edges).
pub const REFERENCE: Rgb = (102, 102, 102);

/// Viridis at five stops, low to high: perceptually ordered and readable under colour-vision
/// deficiencies and in grey.
const SEQUENTIAL: [Rgb; 5] = [(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)];

/// The sequential scale's colour at `f` in [0, 1] (clamped), linear between its stops.
pub fn sequential(f: f64) -> Rgb {
    let f = f.clamp(0.0, 1.0) * (SEQUENTIAL.len() - 1) as f64;
    let i = (f.floor() as usize).min(SEQUENTIAL.len() - 2);
    let t = f - i as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + (f64::from(b) - f64::from(a)) * t).round() as u8;
    let (a, b) = (SEQUENTIAL[i], SEQUENTIAL[i + 1]);
    (mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Survey AUV `k`'s colour.
pub fn vehicle(k: usize) -> Rgb {
    VEHICLES[k % VEHICLES.len()]
}

/// `#rrggbb` of `c`.
pub fn hex((r, g, b): Rgb) -> String {
    format!("#{r:02x}{g:02x}{b:02x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_repeat_after_eight_and_print_as_html_hex() {
        assert_eq!(vehicle(8), vehicle(0));
        assert_ne!(vehicle(1), vehicle(0));
        assert_eq!(hex(vehicle(1)), "#d55e00");
        assert_eq!(hex(CNA), "#000000");
    }

    /// WCAG contrast ratio of `c` against white.
    fn contrast_on_white((r, g, b): Rgb) -> f64 {
        let lin = |v: u8| {
            let v = f64::from(v) / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        let l = 0.2126 * lin(r) + 0.7152 * lin(g) + 0.0722 * lin(b);
        1.05 / (l + 0.05)
    }

    #[test]
    fn every_vehicle_colour_shows_on_white_and_differs_from_the_others() {
        // Okabe-Ito's yellow (240, 228, 66) is 1.3:1 on white; its sky blue and orange, the
        // palette's faintest kept, 2.2:1.
        assert!(contrast_on_white((240, 228, 66)) < 1.5);
        for c in VEHICLES.iter().chain([&CNA, &REFERENCE]) {
            assert!(contrast_on_white(*c) >= 2.0, "{c:?} is {:.2}:1 on white", contrast_on_white(*c));
        }
        let distinct: std::collections::BTreeSet<Rgb> = VEHICLES.iter().copied().chain([CNA, REFERENCE]).collect();
        assert_eq!(distinct.len(), VEHICLES.len() + 2);
    }

    #[test]
    fn the_sequential_scale_runs_from_its_first_stop_to_its_last() {
        assert_eq!(sequential(0.0), (68, 1, 84));
        assert_eq!(sequential(1.0), (253, 231, 37));
        assert_eq!(sequential(-3.0), sequential(0.0));
        assert_eq!(sequential(0.125), (64, 42, 112));
    }
}
