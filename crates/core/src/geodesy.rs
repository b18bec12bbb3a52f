//! WGS-84 geodesy for field logs (Gill 2013, §2.4.2 and §3.3; docs/models.md#gill-geodesy):
//! geodetic latitude/longitude/height
//! ↔ Earth-centred Earth-fixed (ECEF) ↔ a local east/north/up tangent plane about a configured
//! origin, all in f64, plus an emulation of the UI AUV's float32 lat/lon storage.
//!
//! Latitude and longitude travel together as [`LatLon`], which can only be built validated, so a
//! swapped or out-of-range pair is caught where it enters. Log positions are 2-D: a [`LocalFrame`]
//! maps a lat/lon at the origin's height to the tangent-plane (east, north) and back, exactly
//! inverse to each other.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// WGS-84 semi-major axis (m).
pub const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// First eccentricity squared, f(2 − f).
const E2: f64 = WGS84_F * (2.0 - WGS84_F);

#[derive(Debug, Clone, PartialEq, Error)]
pub enum GeodesyError {
    #[error("latitude {0} deg is outside [-90, 90] or not finite")]
    Latitude(f64),
    #[error("longitude {0} deg is outside [-180, 180] or not finite")]
    Longitude(f64),
    #[error("height {0} m is not finite")]
    Height(f64),
    #[error("east/north ({east}, {north}) m is not finite or too far from the origin (allowed within {max} m)")]
    Plane { east: f64, north: f64, max: f64 },
}

/// A validated geodetic latitude and longitude in degrees (WGS-84).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "LatLonSpec", into = "LatLonSpec")]
pub struct LatLon {
    lat_deg: f64,
    lon_deg: f64,
}

/// The serde shape of [`LatLon`]: named fields, so a file can't swap them silently.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct LatLonSpec {
    lat_deg: f64,
    lon_deg: f64,
}

impl TryFrom<LatLonSpec> for LatLon {
    type Error = GeodesyError;
    fn try_from(s: LatLonSpec) -> Result<Self, GeodesyError> {
        LatLon::new(s.lat_deg, s.lon_deg)
    }
}

impl From<LatLon> for LatLonSpec {
    fn from(l: LatLon) -> Self {
        LatLonSpec { lat_deg: l.lat_deg, lon_deg: l.lon_deg }
    }
}

impl LatLon {
    /// Checks |lat| ≤ 90 and lon ∈ [−180, 180], both finite.
    pub fn new(lat_deg: f64, lon_deg: f64) -> Result<Self, GeodesyError> {
        if !(lat_deg.is_finite() && lat_deg.abs() <= 90.0) {
            return Err(GeodesyError::Latitude(lat_deg));
        }
        if !(lon_deg.is_finite() && lon_deg.abs() <= 180.0) {
            return Err(GeodesyError::Longitude(lon_deg));
        }
        Ok(LatLon { lat_deg, lon_deg })
    }
    pub fn lat_deg(self) -> f64 {
        self.lat_deg
    }
    pub fn lon_deg(self) -> f64 {
        self.lon_deg
    }
}

/// A geodetic position: latitude/longitude and height above the WGS-84 ellipsoid (m). In files:
/// `{ lat_deg = …, lon_deg = …, height_m = … }`, height optional (default 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GeodeticSpec", into = "GeodeticSpec")]
pub struct Geodetic {
    latlon: LatLon,
    height_m: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GeodeticSpec {
    lat_deg: f64,
    lon_deg: f64,
    #[serde(default)]
    height_m: f64,
}

impl TryFrom<GeodeticSpec> for Geodetic {
    type Error = GeodesyError;
    fn try_from(s: GeodeticSpec) -> Result<Self, GeodesyError> {
        Geodetic::new(LatLon::new(s.lat_deg, s.lon_deg)?, s.height_m)
    }
}

impl From<Geodetic> for GeodeticSpec {
    fn from(g: Geodetic) -> Self {
        GeodeticSpec { lat_deg: g.latlon.lat_deg, lon_deg: g.latlon.lon_deg, height_m: g.height_m }
    }
}

impl Geodetic {
    pub fn new(latlon: LatLon, height_m: f64) -> Result<Self, GeodesyError> {
        if !height_m.is_finite() {
            return Err(GeodesyError::Height(height_m));
        }
        Ok(Geodetic { latlon, height_m })
    }
    pub fn latlon(self) -> LatLon {
        self.latlon
    }
    pub fn height_m(self) -> f64 {
        self.height_m
    }

    /// Earth-centred Earth-fixed coordinates.
    pub fn to_ecef(self) -> Ecef {
        let (sin_lat, cos_lat) = self.latlon.lat_deg.to_radians().sin_cos();
        let (sin_lon, cos_lon) = self.latlon.lon_deg.to_radians().sin_cos();
        let n = prime_vertical_radius(sin_lat);
        let h = self.height_m;
        Ecef { x: (n + h) * cos_lat * cos_lon, y: (n + h) * cos_lat * sin_lon, z: (n * (1.0 - E2) + h) * sin_lat }
    }
}

/// Radius of curvature in the prime vertical, N(φ).
fn prime_vertical_radius(sin_lat: f64) -> f64 {
    WGS84_A / (1.0 - E2 * sin_lat * sin_lat).sqrt()
}

/// Earth-centred Earth-fixed Cartesian coordinates (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ecef {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl Ecef {
    /// Geodetic coordinates by fixed-point iteration on latitude, φ = atan2(z + e²N(φ) sin φ, p),
    /// which contracts by ≈ e² per step and stays well-posed at the poles (p → 0). Fails only
    /// on non-finite coordinates.
    pub fn to_geodetic(self) -> Result<Geodetic, GeodesyError> {
        let p = self.x.hypot(self.y);
        let lon = self.y.atan2(self.x);
        let mut lat = self.z.atan2(p * (1.0 - E2));
        for _ in 0..32 {
            let s = lat.sin();
            let next = (self.z + E2 * prime_vertical_radius(s) * s).atan2(p);
            let done = (next - lat).abs() < 1e-15;
            lat = next;
            if done {
                break;
            }
        }
        let (s, c) = lat.sin_cos();
        // Valid at every latitude (no division by cos φ).
        let height_m = p * c + self.z * s - WGS84_A * (1.0 - E2 * s * s).sqrt();
        Geodetic::new(LatLon::new(lat.to_degrees(), lon.to_degrees())?, height_m)
    }
}

/// A point in the local east/north/up tangent plane (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Enu {
    pub east: f64,
    pub north: f64,
    pub up: f64,
}

/// A local east/north/up tangent plane about a geodetic origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    origin: Geodetic,
    origin_ecef: Ecef,
    /// Rows: the east, north and up unit vectors in ECEF.
    axes: [[f64; 3]; 3],
}

/// How far from the origin [`LocalFrame::from_plane`] accepts a point: a local frame is meant
/// for one survey site, and the surface search below is only checked that far.
pub const MAX_PLANE_DISTANCE_M: f64 = 1.0e6;

impl LocalFrame {
    pub fn new(origin: Geodetic) -> Self {
        let (sl, cl) = origin.latlon.lat_deg.to_radians().sin_cos();
        let (so, co) = origin.latlon.lon_deg.to_radians().sin_cos();
        LocalFrame {
            origin,
            origin_ecef: origin.to_ecef(),
            axes: [[-so, co, 0.0], [-sl * co, -sl * so, cl], [cl * co, cl * so, sl]],
        }
    }

    pub fn origin(&self) -> Geodetic {
        self.origin
    }

    pub fn ecef_to_enu(&self, p: Ecef) -> Enu {
        let d = [p.x - self.origin_ecef.x, p.y - self.origin_ecef.y, p.z - self.origin_ecef.z];
        let dot = |a: [f64; 3]| a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
        Enu { east: dot(self.axes[0]), north: dot(self.axes[1]), up: dot(self.axes[2]) }
    }

    pub fn enu_to_ecef(&self, v: Enu) -> Ecef {
        let [e, n, u] = self.axes;
        let o = self.origin_ecef;
        Ecef {
            x: o.x + v.east * e[0] + v.north * n[0] + v.up * u[0],
            y: o.y + v.east * e[1] + v.north * n[1] + v.up * u[1],
            z: o.z + v.east * e[2] + v.north * n[2] + v.up * u[2],
        }
    }

    pub fn to_enu(&self, g: Geodetic) -> Enu {
        self.ecef_to_enu(g.to_ecef())
    }

    pub fn to_geodetic(&self, v: Enu) -> Result<Geodetic, GeodesyError> {
        self.enu_to_ecef(v).to_geodetic()
    }

    /// (east, north) of a lat/lon taken at the origin's height: how 2-D log positions enter the
    /// metric frame.
    pub fn to_plane(&self, ll: LatLon) -> (f64, f64) {
        let v = self.to_enu(Geodetic { latlon: ll, height_m: self.origin.height_m });
        (v.east, v.north)
    }

    /// The lat/lon at the origin's height whose [`to_plane`](Self::to_plane) is (east, north):
    /// searches the up coordinate (the surface falls away as d²/2R), which converges to
    /// ~10 nm (the ECEF round-off) in a few steps because ∂height/∂up ≈ 1 near the origin.
    pub fn from_plane(&self, east: f64, north: f64) -> Result<LatLon, GeodesyError> {
        if !(east.is_finite() && north.is_finite() && east.hypot(north) <= MAX_PLANE_DISTANCE_M) {
            return Err(GeodesyError::Plane { east, north, max: MAX_PLANE_DISTANCE_M });
        }
        let mut up = 0.0;
        let mut g = self.to_geodetic(Enu { east, north, up })?;
        for _ in 0..16 {
            let dh = g.height_m - self.origin.height_m;
            if dh.abs() < 1e-8 {
                break;
            }
            up -= dh;
            g = self.to_geodetic(Enu { east, north, up })?;
        }
        Ok(g.latlon)
    }
}

/// How a device stored latitude and longitude (Gill 2013, §3.3; docs/models.md#gill-geodesy).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LatLonStorage {
    /// Full f64: nothing lost.
    #[default]
    F64,
    /// IEEE float32, round to nearest (the UI AUV's Rabbit).
    F32,
    /// float32 with one more significand bit lost, as in the thesis's buoy logs (1.137 m E ×
    /// 0.849 m N at Lake Pend Oreille). How the bit was lost is unknown ("likely ... during the
    /// packet handling"); reconstructed here as round-half-even to the coarser grid.
    F32LostBit,
}

impl LatLonStorage {
    /// The stored value of a lat/lon. Stays valid: ±90 and ±180 are representable in f32 and
    /// rounding never crosses a representable bound.
    pub fn store(self, ll: LatLon) -> LatLon {
        LatLon { lat_deg: self.store_deg(ll.lat_deg), lon_deg: self.store_deg(ll.lon_deg) }
    }

    fn store_deg(self, deg: f64) -> f64 {
        match self {
            LatLonStorage::F64 => deg,
            LatLonStorage::F32 => f64::from(deg as f32),
            LatLonStorage::F32LostBit => f64::from(drop_low_bit(deg as f32)),
        }
    }
}

/// Rounds a float32 to an even significand (one bit fewer), ties to the neighbour whose next bit
/// is clear. The IEEE layout is sign-magnitude, so this is symmetric in sign, and a carry out of
/// the significand correctly bumps the exponent.
fn drop_low_bit(x: f32) -> f32 {
    let b = x.to_bits();
    if b & 1 == 0 {
        return x;
    }
    f32::from_bits(if b & 2 == 0 { b - 1 } else { b + 1 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn ll(lat: f64, lon: f64) -> LatLon {
        LatLon::new(lat, lon).unwrap()
    }
    fn at(lat: f64, lon: f64, h: f64) -> Geodetic {
        Geodetic::new(ll(lat, lon), h).unwrap()
    }
    fn lon_diff(a: f64, b: f64) -> f64 {
        (a - b + 540.0).rem_euclid(360.0) - 180.0
    }

    #[test]
    fn bad_coordinates_are_typed_errors() {
        assert_eq!(LatLon::new(95.0, 0.0), Err(GeodesyError::Latitude(95.0)));
        assert_eq!(LatLon::new(-90.5, 0.0), Err(GeodesyError::Latitude(-90.5)));
        assert!(matches!(LatLon::new(f64::NAN, 0.0), Err(GeodesyError::Latitude(_))));
        assert_eq!(LatLon::new(0.0, 180.5), Err(GeodesyError::Longitude(180.5)));
        assert!(matches!(LatLon::new(0.0, f64::INFINITY), Err(GeodesyError::Longitude(_))));
        assert!(LatLon::new(90.0, -180.0).is_ok());
        assert!(matches!(Geodetic::new(ll(0.0, 0.0), f64::NAN), Err(GeodesyError::Height(_))));
        let f = LocalFrame::new(at(10.0, 10.0, 0.0));
        assert!(matches!(f.from_plane(2e6, 0.0), Err(GeodesyError::Plane { .. })));
        assert!(matches!(f.from_plane(f64::NAN, 0.0), Err(GeodesyError::Plane { .. })));
        let nan = Enu { east: f64::NAN, north: 0.0, up: 0.0 };
        assert!(f.to_geodetic(nan).is_err());
    }

    #[test]
    fn latlon_toml_is_named_and_validated() {
        #[derive(Debug, Deserialize)]
        struct W {
            o: LatLon,
        }
        #[derive(Debug, Deserialize)]
        struct G {
            o: Geodetic,
        }
        let g: G = toml::from_str("o = { lat_deg = 47.97, lon_deg = -116.5 }").unwrap();
        assert_eq!(g.o, at(47.97, -116.5, 0.0));
        let g: G = toml::from_str("o = { lat_deg = 47.97, lon_deg = -116.5, height_m = 630.0 }").unwrap();
        assert_eq!(g.o.height_m(), 630.0);
        let e = toml::from_str::<G>("o = { lat_deg = 0.0, lon_deg = 200.0 }").unwrap_err().to_string();
        assert!(e.contains("longitude 200"), "{e}");
        let e = toml::from_str::<G>("o = { lat_deg = 0.0, lon_deg = 0.0, height_m = nan }").unwrap_err().to_string();
        assert!(e.contains("height NaN"), "{e}");
        let w: W = toml::from_str("o = { lat_deg = 47.97, lon_deg = -116.5 }").unwrap();
        assert_eq!(w.o, ll(47.97, -116.5));
        let e = toml::from_str::<W>("o = { lat_deg = 95.0, lon_deg = 0.0 }").unwrap_err().to_string();
        assert!(e.contains("latitude 95"), "{e}");
        let e = toml::from_str::<W>("o = { lat = 1.0, lon_deg = 0.0 }").unwrap_err().to_string();
        assert!(e.contains("lat"), "{e}");
    }

    #[test]
    fn ellipsoid_reference_points() {
        // On the equator at the prime meridian ECEF x is the semi-major axis; at the pole z is
        // the semi-minor axis b = 6 356 752.3142 m (published WGS-84 constant).
        let e = at(0.0, 0.0, 0.0).to_ecef();
        assert!((e.x - 6_378_137.0).abs() < 1e-6 && e.y.abs() < 1e-6 && e.z.abs() < 1e-6);
        let p = at(90.0, 0.0, 0.0).to_ecef();
        assert!((p.z - 6_356_752.314_2).abs() < 1e-3 && p.x.abs() < 1e-6, "{p:?}");
        let back = p.to_geodetic().unwrap();
        assert!((back.latlon.lat_deg - 90.0).abs() < 1e-12 && back.height_m.abs() < 1e-6, "{back:?}");
    }

    #[test]
    fn origin_is_zero_and_degree_lengths_match_published_values() {
        for (lat, lon) in [(45.0, 10.0), (0.0, -60.0), (47.97, -116.5)] {
            let f = LocalFrame::new(at(lat, lon, 120.0));
            let o = f.to_enu(at(lat, lon, 120.0));
            assert!(o.east.abs() < 1e-9 && o.north.abs() < 1e-9 && o.up.abs() < 1e-9, "{o:?}");
        }
        // Local scale from a ±0.0005° step (the chord over a whole degree is ~1.4 m short).
        // Published series for 1° of latitude: 111 132.954 − 559.822 cos 2φ + 1.175 cos 4φ m,
        // = 111 131.78 m at 45° (≈ 111 132 m); 1° of longitude on the equator = 111 319.49 m.
        let f = LocalFrame::new(at(45.0, 7.0, 0.0));
        let dn = f.to_plane(ll(45.0005, 7.0)).1 - f.to_plane(ll(44.9995, 7.0)).1;
        let series = 111_132.954 - 559.822 * 90f64.to_radians().cos() + 1.175 * 180f64.to_radians().cos();
        assert!((dn * 1000.0 - series).abs() < 0.01 && (dn * 1000.0 - 111_132.0).abs() < 1.0, "{}", dn * 1000.0);
        let f = LocalFrame::new(at(0.0, 30.0, 0.0));
        let de = f.to_plane(ll(0.0, 30.0005)).0 - f.to_plane(ll(0.0, 29.9995)).0;
        assert!((de * 1000.0 - 111_319.49).abs() < 1.0, "{}", de * 1000.0);
        // East really is east and north really is north.
        let (e, n) = f.to_plane(ll(0.001, 30.001));
        assert!(e > 100.0 && n > 100.0);
    }

    /// Distinct stored values of a coordinate swept finely over a short span, each converted to
    /// metres in the local frame; returns the mean gap between neighbours (m).
    fn grid_spacing_m(storage: LatLonStorage, f: &LocalFrame, site: LatLon, north: bool) -> f64 {
        let mut metres: Vec<f64> = Vec::new();
        for i in 0..20_000 {
            let d = i as f64 * 1e-7;
            let p = if north { ll(site.lat_deg + d, site.lon_deg) } else { ll(site.lat_deg, site.lon_deg + d) };
            let s = storage.store(p);
            let (e, n) = f.to_plane(s);
            let m = if north { n } else { e };
            if metres.last() != Some(&m) {
                metres.push(m);
            }
        }
        assert!(metres.len() > 10, "{} distinct values", metres.len());
        let gaps: Vec<f64> = metres.windows(2).map(|w| w[1] - w[0]).collect();
        let (lo, hi) = gaps.iter().fold((f64::MAX, f64::MIN), |(a, b), &g| (a.min(g), b.max(g)));
        assert!(hi - lo < 1e-3, "uneven grid: {lo}..{hi}");
        gaps.iter().sum::<f64>() / gaps.len() as f64
    }

    #[test]
    fn pend_oreille_float32_grid_matches_the_thesis() {
        let site = ll(47.97, -116.5);
        let f = LocalFrame::new(Geodetic::new(site, 0.0).unwrap());
        let n32 = grid_spacing_m(LatLonStorage::F32, &f, site, true);
        let e32 = grid_spacing_m(LatLonStorage::F32, &f, site, false);
        // 2⁻¹⁸° of latitude and 2⁻¹⁷° of longitude at 47.97° N.
        assert!((n32 - 0.424).abs() < 0.001, "{n32}");
        assert!((e32 - 0.570).abs() < 0.001, "{e32}");
        let n31 = grid_spacing_m(LatLonStorage::F32LostBit, &f, site, true);
        let e31 = grid_spacing_m(LatLonStorage::F32LostBit, &f, site, false);
        assert!((n31 - 0.848).abs() < 0.001, "{n31}");
        assert!((e31 - 1.139).abs() < 0.001, "{e31}");
        // The thesis's logged buoy grid: 0.849 m N × 1.137 m E.
        assert!((n31 - 0.849).abs() < 0.003 && (e31 - 1.137).abs() < 0.003);
        // F64 stores exactly.
        assert_eq!(LatLonStorage::F64.store(site), site);
    }

    #[test]
    fn lost_bit_rounds_to_nearest_even_neighbour_symmetrically() {
        let even = 47.97f32.to_bits() & !3; // significand ends in binary 00
        let f = f32::from_bits;
        assert_eq!(drop_low_bit(f(even)), f(even));
        assert_eq!(drop_low_bit(f(even + 1)), f(even)); // odd, next bit clear: down
        assert_eq!(drop_low_bit(f(even + 3)), f(even + 4)); // odd, next bit set: up
        assert_eq!(drop_low_bit(-f(even + 3)), -f(even + 4));
        // Carry out of the significand: the largest odd significand below 64 rounds to 64.
        assert_eq!(drop_low_bit(f(64f32.to_bits() - 1)), 64.0);
        assert_eq!(LatLonStorage::F32LostBit.store(ll(90.0, -180.0)), ll(90.0, -180.0));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]
        #[test]
        fn geodetic_enu_round_trip_within_50_km(
            olat in -80.0..80.0f64, olon in -180.0..180.0f64, oh in -100.0..3000.0f64,
            dist in 0.0..50_000.0f64, bearing in 0.0..std::f64::consts::TAU, h in -200.0..2000.0f64,
        ) {
            let f = LocalFrame::new(at(olat, olon, oh));
            // A point within 50 km, placed by spherical offsets so the generator is independent
            // of the code under test.
            let dlat = (dist * bearing.cos() / 111_000.0).clamp(-89.9 - olat, 89.9 - olat);
            let lat = olat + dlat;
            let lon = lon_diff(olon + dist * bearing.sin() / (111_000.0 * lat.to_radians().cos()), 0.0);
            let g = at(lat, lon, h);
            let back = f.to_geodetic(f.to_enu(g)).unwrap();
            prop_assert!((back.latlon.lat_deg - lat).abs() < 1e-9);
            prop_assert!(lon_diff(back.latlon.lon_deg, lon).abs() < 1e-9);
            prop_assert!((back.height_m - h).abs() < 1e-6);
        }

        #[test]
        fn plane_round_trip_is_exact_inverse(
            olat in -85.0..85.0f64, olon in -180.0..180.0f64, oh in -100.0..3000.0f64,
            e in -50_000.0..50_000.0f64, n in -50_000.0..50_000.0f64,
        ) {
            let f = LocalFrame::new(at(olat, olon, oh));
            let p = f.from_plane(e, n).unwrap();
            let (e2, n2) = f.to_plane(p);
            prop_assert!((e2 - e).abs() < 1e-6 && (n2 - n).abs() < 1e-6, "{} {}", e2 - e, n2 - n);
        }
    }
}
