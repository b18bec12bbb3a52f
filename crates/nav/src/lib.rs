//! coopnav-nav: survey-AUV navigation with one-way-travel-time (OWTT) ranges, after Gill (2013).
//!
//! It owns the generic EKF, the AUV and surface-vehicle filters, the OWTT range model, the
//! mini-packet codec, the ranging cycles and the RTS smoother.
