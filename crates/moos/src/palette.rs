//! The one colour of each vehicle in every output that draws one (the report's plots, the replay
//! page): survey AUV k in the Okabe–Ito palette's colour k (Okabe and Ito, "Color Universal
//! Design", 2008), chosen to stay distinct under the common colour-vision deficiencies, and the
//! CNA in its black. Beyond seven AUVs the colours repeat.

/// An sRGB colour.
pub type Rgb = (u8, u8, u8);

/// The survey AUVs' colours, by index: blue, vermillion, bluish green, reddish purple, sky blue,
/// orange, yellow.
pub const VEHICLES: [Rgb; 7] =
    [(0, 114, 178), (213, 94, 0), (0, 158, 115), (204, 121, 167), (86, 180, 233), (230, 159, 0), (240, 228, 66)];

/// The CNA's colour.
pub const CNA: Rgb = (0, 0, 0);

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
    fn colours_repeat_after_seven_and_print_as_html_hex() {
        assert_eq!(vehicle(7), vehicle(0));
        assert_ne!(vehicle(1), vehicle(0));
        assert_eq!(hex(vehicle(1)), "#d55e00");
        assert_eq!(hex(CNA), "#000000");
    }
}
