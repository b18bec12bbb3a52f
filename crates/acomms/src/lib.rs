//! coopnav-acomms: the acoustic link, after Nams (2014).
//!
//! It owns the WHOI Micro-Modem rate table, transmission-loss models (analytic and BELLHOP),
//! packet success, TDMA, the bit-exact message codecs, the packet-success tracker and the
//! adaptive rate selector.
