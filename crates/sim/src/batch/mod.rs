//! Many runs at once: seeded Monte Carlo comparisons of CNA policies ([`mc`]), Gill's
//! buoy-location grid ([`grid`]) and coefficient tuning ([`tune`]), Nams's experiment of cells ×
//! behaviours × runs ([`nams`], each cell an engine scenario from [`nams_setup`]), the
//! sweep file and its expansion into cells ([`sweep`]), and the work estimates that check a
//! set-up's size before it runs ([`work`]).

pub mod advise;
pub mod grid;
pub mod mc;
pub mod nams;
pub mod nams_setup;
pub mod sweep;
pub mod tune;
pub mod work;

#[cfg(test)]
mod tests;
