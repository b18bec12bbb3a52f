//! coopnav-core: the vocabulary every other coopnav crate speaks.
//!
//! It owns the frame and unit conventions (x east, y north, z depth positive down; SI units;
//! math-convention headings inside, compass headings only at the edge), seeded randomness that
//! keeps Monte Carlo runs bit-identical on any thread count, and survey missions (waypoints,
//! lawnmower patterns, time-stamped tracks with linear interpolation), and WGS-84 geodesy (lat/lon
//! ↔ ECEF ↔ local east/north/up) for field logs, and the work limits every input is checked
//! against before it is run, and the collector that reports every bad field of an input at once.
//! It deliberately knows nothing about planners, filters or modems.

pub mod angle;
pub mod bathymetry;
pub mod geodesy;
pub mod geometry;
pub mod kinematics;
pub mod limits;
pub mod mission;
pub mod rng;
pub mod validation;

pub use angle::{rem_euclid, wrap_pi, CompassDeg, Degrees, Heading, Radians};
pub use bathymetry::{Bathymetry, BathymetryError, Shelf};
pub use geodesy::{Ecef, Enu, GeodesyError, Geodetic, LatLon, LatLonStorage, LocalFrame};
pub use geometry::{hypot_within, Rect, Vec3};
pub use kinematics::{DepthTarget, Iver2, Iver2Params, Iver2State, Waypoint};
pub use mission::{DepthProfile, Lawnmower, SurveyPath, Track, TrackError, TrackSample};
pub use rng::{run_seed, SeedStream};
