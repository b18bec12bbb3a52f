//! LCM's UDP multicast transport: the `udpm://` URL, the packet formats, bounded reassembly of
//! fragmented messages, and a publish/subscribe endpoint ([`Udpm`]).
//!
//! The protocol, restated from lcm-proj/lcm's `docs/content/udp-multicast-protocol.md` and checked
//! against `lcm/lcm_udpm.c` and `lcm/udpm_util.h`:
//! - every message goes to one multicast group and port (default `239.255.76.67:7667`, TTL 0 so
//!   nothing leaves the host); all header fields are big-endian;
//! - a *short* message is one datagram: magic `0x4c433032` ("LC02"), a `u32` sequence number, the
//!   channel name NUL-terminated, then the payload. lcm sends it short when channel + NUL +
//!   payload is at most 65499 bytes (on Linux; 1435 on macOS);
//! - otherwise it is *fragmented*: each datagram has magic `0x4c433033` ("LC03"), the sequence
//!   number (the same for every fragment, from the same counter as short messages), the `u32`
//!   payload size (not counting the channel), the `u32` offset of this fragment's data in the
//!   payload, a `u16` fragment number and a `u16` fragment count (20 bytes in all). Fragment 0
//!   carries the NUL-terminated channel before its data. lcm cuts fragments of 65487 bytes of
//!   (channel + NUL +) data, so fragment 0 holds `65487 - (channel + 1)` payload bytes; the count
//!   is `ceil((channel + 1 + payload) / 65487)`, at most 65535;
//! - channel names are at most 63 bytes (`LCM_MAX_CHANNEL_NAME_LENGTH`), messages at most 2^28
//!   bytes (`LCM_MAX_MESSAGE_SIZE`); lcm keys partial messages by sender and sequence number,
//!   drops a partial when a fragment of the same key names another size, and bounds the partials
//!   to 1000 and 16 MiB in all, evicting the oldest;
//! - a subscription's channel is a regular expression matched against the whole name
//!   (`lcm/lcm.c` compiles `^CHANNEL$`); [`Udpm::subscribe`] takes exact names, and
//!   [`Udpm::subscribe_regex`] patterns;
//! - a receiver binds the group's port with `SO_REUSEADDR` and joins the group; a sender sets the
//!   multicast TTL and multicast loopback on.

use std::collections::HashMap;
use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4, UdpSocket};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use socket2::{Domain, Protocol, Socket, Type};

use crate::error::TransportError;

/// "LC02": a message in one datagram.
pub const MAGIC_SHORT: u32 = 0x4c43_3032;
/// "LC03": one fragment of a message.
pub const MAGIC_LONG: u32 = 0x4c43_3033;
/// The largest channel + NUL + payload sent as a short message (lcm on Linux).
pub const SHORT_MESSAGE_MAX_SIZE: usize = 65499;
/// The bytes of (channel + NUL +) payload in one fragment (lcm on Linux).
pub const FRAGMENT_MAX_PAYLOAD: usize = 65487;
/// The longest channel name, in bytes.
pub const MAX_CHANNEL_LEN: usize = 63;
/// The largest message lcm accepts.
pub const MAX_MESSAGE_SIZE: usize = 1 << 28;
/// The short header's length.
pub const SHORT_HEADER_LEN: usize = 8;
/// The fragment header's length.
pub const LONG_HEADER_LEN: usize = 20;
/// lcm's default URL.
pub const DEFAULT_URL: &str = "udpm://239.255.76.67:7667?ttl=0";

/// A parsed `udpm://ADDR:PORT?ttl=N&recv_buf_size=B` URL.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Url {
    pub group: Ipv4Addr,
    pub port: u16,
    pub ttl: u8,
    /// The kernel receive buffer to ask for, if any.
    pub recv_buf_size: Option<usize>,
}

impl Default for Url {
    fn default() -> Self {
        Self { group: Ipv4Addr::new(239, 255, 76, 67), port: 7667, ttl: 0, recv_buf_size: None }
    }
}

impl Url {
    /// Parses a URL. An empty address part means lcm's default group and port; unknown options
    /// are refused (lcm only warns, but a typo in `ttl` must not put packets on the network).
    pub fn parse(url: &str) -> Result<Self, TransportError> {
        let bad = |reason: &str| TransportError::BadUrl { url: url.to_string(), reason: reason.to_string() };
        let rest = url.strip_prefix("udpm://").ok_or_else(|| bad("only the udpm:// provider is supported"))?;
        let (target, query) = rest.split_once('?').unwrap_or((rest, ""));
        let mut out = Self::default();
        if !target.is_empty() {
            let (addr, port) = match target.split_once(':') {
                Some((a, p)) => (a, Some(p)),
                None => (target, None),
            };
            out.group = addr.parse().map_err(|_| bad("bad multicast address"))?;
            if !out.group.is_multicast() {
                return Err(bad("the address is not a multicast group"));
            }
            if let Some(p) = port {
                out.port = p.parse().map_err(|_| bad("bad port"))?;
            }
        }
        for pair in query.split('&').filter(|s| !s.is_empty()) {
            let (key, value) = pair.split_once('=').ok_or_else(|| bad("an option without a value"))?;
            match key {
                "ttl" => out.ttl = value.parse().map_err(|_| bad("ttl must be 0..=255"))?,
                "recv_buf_size" => out.recv_buf_size = Some(value.parse().map_err(|_| bad("bad recv_buf_size"))?),
                _ => return Err(bad("unknown option")),
            }
        }
        Ok(out)
    }

    /// The group's socket address.
    pub fn socket_addr(&self) -> SocketAddrV4 {
        SocketAddrV4::new(self.group, self.port)
    }
}

fn check_channel(channel: &str) -> Result<(), TransportError> {
    if channel.len() > MAX_CHANNEL_LEN || channel.as_bytes().contains(&0) {
        Err(TransportError::BadChannel(channel.to_string()))
    } else {
        Ok(())
    }
}

/// The datagrams lcm sends for one message, short or fragmented exactly as lcm cuts them.
pub fn encode_datagrams(seq: u32, channel: &str, payload: &[u8]) -> Result<Vec<Vec<u8>>, TransportError> {
    check_channel(channel)?;
    if payload.len() > MAX_MESSAGE_SIZE {
        return Err(TransportError::TooLarge(payload.len()));
    }
    let channel_part = channel.len() + 1;
    let total = channel_part + payload.len();
    if total <= SHORT_MESSAGE_MAX_SIZE {
        let mut d = Vec::with_capacity(SHORT_HEADER_LEN + total);
        d.extend_from_slice(&MAGIC_SHORT.to_be_bytes());
        d.extend_from_slice(&seq.to_be_bytes());
        d.extend_from_slice(channel.as_bytes());
        d.push(0);
        d.extend_from_slice(payload);
        return Ok(vec![d]);
    }
    let count = total.div_ceil(FRAGMENT_MAX_PAYLOAD);
    let count = u16::try_from(count).map_err(|_| TransportError::TooLarge(payload.len()))?;
    let mut out = Vec::with_capacity(count.into());
    let mut offset = 0usize;
    for number in 0..count {
        let room = if number == 0 { FRAGMENT_MAX_PAYLOAD - channel_part } else { FRAGMENT_MAX_PAYLOAD };
        let len = room.min(payload.len() - offset);
        let mut d = Vec::with_capacity(LONG_HEADER_LEN + channel_part + len);
        d.extend_from_slice(&MAGIC_LONG.to_be_bytes());
        d.extend_from_slice(&seq.to_be_bytes());
        d.extend_from_slice(&(payload.len() as u32).to_be_bytes());
        d.extend_from_slice(&(offset as u32).to_be_bytes());
        d.extend_from_slice(&number.to_be_bytes());
        d.extend_from_slice(&count.to_be_bytes());
        if number == 0 {
            d.extend_from_slice(channel.as_bytes());
            d.push(0);
        }
        d.extend_from_slice(&payload[offset..offset + len]);
        offset += len;
        out.push(d);
    }
    debug_assert_eq!(offset, payload.len());
    Ok(out)
}

/// One datagram, parsed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Packet<'a> {
    Short { seq: u32, channel: &'a str, payload: &'a [u8] },
    Fragment(Fragment<'a>),
}

/// One fragment of a message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fragment<'a> {
    pub seq: u32,
    /// The whole payload's size.
    pub payload_size: u32,
    pub offset: u32,
    pub number: u16,
    pub count: u16,
    /// The channel (fragment 0 only).
    pub channel: Option<&'a str>,
    pub data: &'a [u8],
}

/// Why a datagram was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BadPacket {
    /// Shorter than its header.
    Short,
    /// Neither magic.
    Magic,
    /// No NUL in reach, longer than 63 bytes, or not UTF-8.
    Channel,
    /// A fragment number not below the count, or data beyond the payload size.
    Fragment,
}

fn be32(b: &[u8]) -> u32 {
    u32::from_be_bytes(b[..4].try_into().expect("4 bytes"))
}

fn be16(b: &[u8]) -> u16 {
    u16::from_be_bytes(b[..2].try_into().expect("2 bytes"))
}

fn split_channel(b: &[u8]) -> Result<(&str, &[u8]), BadPacket> {
    let reach = &b[..b.len().min(MAX_CHANNEL_LEN + 1)];
    let nul = reach.iter().position(|&c| c == 0).ok_or(BadPacket::Channel)?;
    let channel = std::str::from_utf8(&b[..nul]).map_err(|_| BadPacket::Channel)?;
    Ok((channel, &b[nul + 1..]))
}

/// Parses one datagram, checking every length against its size.
pub fn parse_datagram(d: &[u8]) -> Result<Packet<'_>, BadPacket> {
    if d.len() < SHORT_HEADER_LEN {
        return Err(BadPacket::Short);
    }
    let seq = be32(&d[4..]);
    match be32(d) {
        MAGIC_SHORT => {
            let (channel, payload) = split_channel(&d[SHORT_HEADER_LEN..])?;
            Ok(Packet::Short { seq, channel, payload })
        }
        MAGIC_LONG => {
            if d.len() < LONG_HEADER_LEN {
                return Err(BadPacket::Short);
            }
            let payload_size = be32(&d[8..]);
            let offset = be32(&d[12..]);
            let number = be16(&d[16..]);
            let count = be16(&d[18..]);
            let (channel, data) = if number == 0 {
                let (c, rest) = split_channel(&d[LONG_HEADER_LEN..])?;
                (Some(c), rest)
            } else {
                (None, &d[LONG_HEADER_LEN..])
            };
            if number >= count || u64::from(offset) + data.len() as u64 > u64::from(payload_size) {
                return Err(BadPacket::Fragment);
            }
            Ok(Packet::Fragment(Fragment { seq, payload_size, offset, number, count, channel, data }))
        }
        _ => Err(BadPacket::Magic),
    }
}

/// Bounds on reassembly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// The largest message assembled.
    pub max_message_size: usize,
    /// The most messages in assembly at once.
    pub max_partials: usize,
    /// The most bytes held by messages in assembly.
    pub max_partial_bytes: usize,
    /// A message in assembly with no fragment for this long is dropped.
    pub stale_after: Duration,
}

impl Default for Limits {
    /// lcm's bounds (1000 partials, 16 MiB in all, hence messages of at most 16 MiB), and 2 s
    /// before a partial is stale.
    fn default() -> Self {
        Self {
            max_message_size: 1 << 24,
            max_partials: 1000,
            max_partial_bytes: 1 << 24,
            stale_after: Duration::from_secs(2),
        }
    }
}

#[derive(Debug)]
struct Partial {
    channel: Option<String>,
    data: Vec<u8>,
    count: u16,
    received: Vec<u64>,
    remaining: u16,
    last: Instant,
}

/// A message put back together, with its channel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Assembled {
    pub channel: String,
    pub data: Vec<u8>,
    pub seq: u32,
}

/// Puts fragmented messages back together, within [`Limits`]: keyed by sender and sequence number
/// (as lcm keys them), a duplicate fragment counted once, a fragment naming another size or count
/// restarting its message, the oldest partial evicted when the count or bytes would be exceeded,
/// and late duplicates of the last 64 completed messages ignored.
#[derive(Debug, Default)]
pub struct Reassembler {
    limits: Limits,
    partials: HashMap<(SocketAddr, u32), Partial>,
    /// The last [`RECENT`] messages completed, whose late duplicate fragments are ignored rather
    /// than starting a message that can never complete.
    recent: std::collections::VecDeque<(SocketAddr, u32)>,
    bytes: usize,
    dropped: u64,
}

/// How many completed messages a [`Reassembler`] remembers.
const RECENT: usize = 64;

impl Reassembler {
    /// A reassembler with these bounds.
    pub fn new(limits: Limits) -> Self {
        Self { limits, ..Self::default() }
    }

    /// Messages in assembly now.
    pub fn partials(&self) -> usize {
        self.partials.len()
    }

    /// Bytes held by messages in assembly.
    pub fn bytes_held(&self) -> usize {
        self.bytes
    }

    /// Messages given up (stale, evicted, inconsistent or over the limits).
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    fn remove(&mut self, key: &(SocketAddr, u32)) {
        if let Some(p) = self.partials.remove(key) {
            self.bytes -= p.data.len();
            self.dropped += 1;
        }
    }

    /// Takes one fragment from `from`, received at `now`; returns the message it completes.
    pub fn push(&mut self, from: SocketAddr, f: &Fragment<'_>, now: Instant) -> Option<Assembled> {
        let stale: Vec<_> = self
            .partials
            .iter()
            .filter(|(_, p)| now.saturating_duration_since(p.last) > self.limits.stale_after)
            .map(|(k, _)| *k)
            .collect();
        for k in &stale {
            self.remove(k);
        }
        let size = f.payload_size as usize;
        let key = (from, f.seq);
        if self.recent.contains(&key) {
            return None;
        }
        if self.partials.get(&key).is_some_and(|p| p.data.len() != size || p.count != f.count) {
            self.remove(&key);
        }
        // A message must fit its fragments (each at most one datagram) and the limits.
        let fits_fragments = size as u64 <= u64::from(f.count) * 65535;
        if size > self.limits.max_message_size || size > self.limits.max_partial_bytes || !fits_fragments {
            self.dropped += 1;
            return None;
        }
        if !self.partials.contains_key(&key) {
            while self.partials.len() >= self.limits.max_partials || self.bytes + size > self.limits.max_partial_bytes {
                let oldest = *self.partials.iter().min_by_key(|(_, p)| p.last).map(|(k, _)| k)?;
                self.remove(&oldest);
            }
            self.bytes += size;
            self.partials.insert(
                key,
                Partial {
                    channel: None,
                    data: vec![0; size],
                    count: f.count,
                    received: vec![0; usize::from(f.count).div_ceil(64)],
                    remaining: f.count,
                    last: now,
                },
            );
        }
        let p = self.partials.get_mut(&key).expect("inserted above");
        let (word, bit) = (usize::from(f.number) / 64, 1u64 << (f.number % 64));
        if p.received[word] & bit != 0 {
            return None;
        }
        p.received[word] |= bit;
        p.remaining -= 1;
        p.last = now;
        if let Some(c) = f.channel {
            p.channel = Some(c.to_string());
        }
        let start = f.offset as usize;
        p.data[start..start + f.data.len()].copy_from_slice(f.data);
        if p.remaining > 0 {
            return None;
        }
        let p = self.partials.remove(&key).expect("present");
        self.bytes -= p.data.len();
        if self.recent.len() == RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back(key);
        // Fragment 0 carries the channel; one built without it (by hand) cannot be delivered.
        let Some(channel) = p.channel else {
            self.dropped += 1;
            return None;
        };
        Some(Assembled { channel, data: p.data, seq: f.seq })
    }
}

/// A message received on a subscribed channel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Message {
    pub channel: String,
    pub data: Vec<u8>,
    pub seq: u32,
    pub from: SocketAddr,
    /// When the last datagram arrived, microseconds since the epoch.
    pub recv_utime: i64,
}

/// What a [`Udpm`] delivers.
#[derive(Debug, Clone)]
enum Subscription {
    Exact(String),
    Pattern(regex::Regex),
    All,
}

/// An LCM UDP multicast endpoint: publishes to the group, and once subscribed receives from it.
#[derive(Debug)]
pub struct Udpm {
    url: Url,
    send: UdpSocket,
    recv: Option<UdpSocket>,
    seq: u32,
    subscriptions: Vec<Subscription>,
    reassembler: Reassembler,
    buf: Vec<u8>,
    bad_datagrams: u64,
    /// Whether the receiving socket is in non-blocking mode now.
    nonblocking: bool,
}

fn now_utime() -> i64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_micros() as i64)
}

impl Udpm {
    /// An endpoint on `url` (see [`Url::parse`]). Only the sending socket is made here; the
    /// receiving one is bound and joined at the first subscription, as lcm does.
    pub fn new(url: &str) -> Result<Self, TransportError> {
        let url = Url::parse(url)?;
        let send = Socket::new(Domain::IPV4, Type::DGRAM, Some(Protocol::UDP))?;
        send.set_multicast_ttl_v4(u32::from(url.ttl))?;
        send.set_multicast_loop_v4(true)?;
        Ok(Self {
            url,
            send: send.into(),
            recv: None,
            seq: 0,
            subscriptions: Vec::new(),
            reassembler: Reassembler::new(Limits::default()),
            buf: vec![0; 65536],
            bad_datagrams: 0,
            nonblocking: false,
        })
    }

    /// The URL in use.
    pub fn url(&self) -> Url {
        self.url
    }

    /// Replaces the reassembly bounds (dropping messages in assembly).
    pub fn set_limits(&mut self, limits: Limits) {
        self.reassembler = Reassembler::new(limits);
    }

    /// Publishes one message.
    pub fn publish(&mut self, channel: &str, payload: &[u8]) -> Result<(), TransportError> {
        let datagrams = encode_datagrams(self.seq, channel, payload)?;
        self.seq = self.seq.wrapping_add(1);
        let dest = SocketAddr::V4(self.url.socket_addr());
        for d in &datagrams {
            self.send.send_to(d, dest)?;
        }
        Ok(())
    }

    fn ensure_receiver(&mut self) -> Result<(), TransportError> {
        if self.recv.is_some() {
            return Ok(());
        }
        let s = Socket::new(Domain::IPV4, Type::DGRAM, Some(Protocol::UDP))?;
        s.set_reuse_address(true)?;
        if let Some(size) = self.url.recv_buf_size {
            s.set_recv_buffer_size(size)?;
        }
        // Bound to the group's address (as lcm does on Linux), so only the group's datagrams come.
        s.bind(&SocketAddr::V4(self.url.socket_addr()).into())?;
        s.join_multicast_v4(&self.url.group, &Ipv4Addr::UNSPECIFIED)?;
        self.recv = Some(s.into());
        Ok(())
    }

    /// Receives messages on `channel` (its exact name) from now on.
    pub fn subscribe(&mut self, channel: &str) -> Result<(), TransportError> {
        check_channel(channel)?;
        self.ensure_receiver()?;
        self.subscriptions.push(Subscription::Exact(channel.to_string()));
        Ok(())
    }

    /// Receives messages on every channel the regular expression matches as a whole, from now on.
    /// lcm subscribes with `^PATTERN$` (GLib's PCRE); this anchors `^(?:PATTERN)$` (the `regex`
    /// crate's syntax), so an alternation `A|B` means either name whole.
    pub fn subscribe_regex(&mut self, pattern: &str) -> Result<(), TransportError> {
        let re = regex::Regex::new(&format!("^(?:{pattern})$"))
            .map_err(|e| TransportError::BadPattern { pattern: pattern.to_string(), reason: e.to_string() })?;
        self.ensure_receiver()?;
        self.subscriptions.push(Subscription::Pattern(re));
        Ok(())
    }

    /// Receives messages on every channel from now on.
    pub fn subscribe_all(&mut self) -> Result<(), TransportError> {
        self.ensure_receiver()?;
        self.subscriptions.push(Subscription::All);
        Ok(())
    }

    fn wants(&self, channel: &str) -> bool {
        self.subscriptions.iter().any(|s| match s {
            Subscription::All => true,
            Subscription::Exact(c) => c == channel,
            Subscription::Pattern(re) => re.is_match(channel),
        })
    }

    /// The next message on a subscribed channel, or `None` once `timeout` has passed without one.
    /// Malformed datagrams are dropped (and counted). Without a subscription it returns `None` at
    /// once.
    pub fn recv_timeout(&mut self, timeout: Duration) -> Result<Option<Message>, TransportError> {
        let deadline = Instant::now() + timeout;
        // Past the deadline (at once for a zero timeout) the datagrams already queued are still
        // read, without waiting, up to this many.
        const DRAIN: usize = 4096;
        let mut drained = 0;
        loop {
            let Some(sock) = self.recv.as_ref() else { return Ok(None) };
            let left = deadline.saturating_duration_since(Instant::now());
            let past = left.is_zero();
            if past {
                drained += 1;
                if drained > DRAIN {
                    return Ok(None);
                }
            } else {
                sock.set_read_timeout(Some(left))?;
            }
            if past != self.nonblocking {
                sock.set_nonblocking(past)?;
                self.nonblocking = past;
            }
            let (n, from) = match sock.recv_from(&mut self.buf) {
                Ok(r) => r,
                Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {
                    return Ok(None);
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e.into()),
            };
            let recv_utime = now_utime();
            match parse_datagram(&self.buf[..n]) {
                Ok(Packet::Short { seq, channel, payload }) => {
                    if self.wants(channel) {
                        let (channel, data) = (channel.to_string(), payload.to_vec());
                        return Ok(Some(Message { channel, data, seq, from, recv_utime }));
                    }
                }
                Ok(Packet::Fragment(f)) => {
                    let done = self.reassembler.push(from, &f, Instant::now());
                    if let Some(a) = done {
                        if self.wants(&a.channel) {
                            return Ok(Some(Message {
                                channel: a.channel,
                                data: a.data,
                                seq: a.seq,
                                from,
                                recv_utime,
                            }));
                        }
                    }
                }
                Err(_) => self.bad_datagrams += 1,
            }
        }
    }

    /// Datagrams dropped as malformed so far.
    pub fn bad_datagrams(&self) -> u64 {
        self.bad_datagrams
    }

    /// Messages given up in reassembly so far (see [`Reassembler::dropped`]).
    pub fn dropped_messages(&self) -> u64 {
        self.reassembler.dropped()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_parse_to_lcm_defaults_and_options() {
        assert_eq!(Url::parse(DEFAULT_URL).unwrap(), Url::default());
        assert_eq!(Url::parse("udpm://").unwrap(), Url::default());
        let u = Url::parse("udpm://239.1.2.3:9000?ttl=1&recv_buf_size=2097152").unwrap();
        assert_eq!((u.group, u.port, u.ttl, u.recv_buf_size), (Ipv4Addr::new(239, 1, 2, 3), 9000, 1, Some(2097152)));
        for bad in [
            "tcpq://1.2.3.4:5",
            "udpm://10.0.0.1:7667",
            "udpm://239.255.76.67:70000",
            "udpm://?ttl=300",
            "udpm://?tll=0",
        ] {
            assert!(Url::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn short_message_layout() {
        let d = encode_datagrams(7, "AB", &[1, 2, 3]).unwrap();
        assert_eq!(d, vec![vec![0x4c, 0x43, 0x30, 0x32, 0, 0, 0, 7, b'A', b'B', 0, 1, 2, 3]]);
        assert_eq!(parse_datagram(&d[0]), Ok(Packet::Short { seq: 7, channel: "AB", payload: &[1, 2, 3] }));
    }

    #[test]
    fn fragments_are_cut_as_lcm_cuts_them() {
        let channel = "BIG";
        // One byte more than fits a short message.
        let payload: Vec<u8> = (0..SHORT_MESSAGE_MAX_SIZE - channel.len()).map(|i| i as u8).collect();
        let d = encode_datagrams(1, channel, &payload).unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(&d[0][..4], b"LC03");
        assert_eq!(d[0].len(), LONG_HEADER_LEN + FRAGMENT_MAX_PAYLOAD);
        let Packet::Fragment(f1) = parse_datagram(&d[1]).unwrap() else { panic!() };
        assert_eq!(f1.offset as usize, FRAGMENT_MAX_PAYLOAD - channel.len() - 1);
        assert_eq!((f1.number, f1.count, f1.payload_size as usize), (1, 2, payload.len()));
        // The largest short message stays short.
        assert_eq!(encode_datagrams(1, channel, &payload[1..]).unwrap().len(), 1);
    }

    fn reassemble(r: &mut Reassembler, datagrams: &[Vec<u8>], from: SocketAddr, now: Instant) -> Vec<Assembled> {
        datagrams
            .iter()
            .filter_map(|d| match parse_datagram(d).unwrap() {
                Packet::Fragment(f) => r.push(from, &f, now),
                Packet::Short { .. } => panic!("short"),
            })
            .collect()
    }

    #[test]
    fn reassembly_in_any_order_and_with_duplicates() {
        let from: SocketAddr = "127.0.0.1:5000".parse().unwrap();
        let payload: Vec<u8> = (0..200_000u32).map(|i| (i * 7) as u8).collect();
        let mut d = encode_datagrams(9, "X", &payload).unwrap();
        assert_eq!(d.len(), 4);
        d.reverse();
        d.insert(1, d[0].clone());
        let mut r = Reassembler::new(Limits::default());
        let out = reassemble(&mut r, &d, from, Instant::now());
        assert_eq!(out, vec![Assembled { channel: "X".into(), data: payload, seq: 9 }]);
        assert_eq!((r.partials(), r.bytes_held()), (0, 0));
    }

    #[test]
    fn reassembly_is_bounded() {
        let from: SocketAddr = "127.0.0.1:5000".parse().unwrap();
        let now = Instant::now();
        let payload = vec![5u8; 150_000];
        let limits = Limits {
            max_message_size: 200_000,
            max_partials: 2,
            max_partial_bytes: 400_000,
            stale_after: Duration::from_secs(1),
        };
        let mut r = Reassembler::new(limits);
        // Three messages missing their last fragment: only two are kept.
        for seq in 0..3 {
            let d = encode_datagrams(seq, "X", &payload).unwrap();
            assert!(reassemble(&mut r, &d[..d.len() - 1], from, now).is_empty());
        }
        assert_eq!(r.partials(), 2);
        assert_eq!(r.dropped(), 1);
        // Over the message size: refused without allocation.
        let big = encode_datagrams(10, "X", &vec![0u8; 250_000]).unwrap();
        assert!(reassemble(&mut r, &big, from, now).is_empty());
        assert_eq!(r.bytes_held(), 300_000);
        // Stale partials are dropped at the next fragment, which then completes alone.
        let d = encode_datagrams(20, "Y", &payload).unwrap();
        let later = now + Duration::from_secs(5);
        let out = reassemble(&mut r, &d, from, later);
        assert_eq!(out.len(), 1);
        assert_eq!((r.partials(), r.bytes_held()), (0, 0));
    }

    #[test]
    fn a_fragment_naming_another_size_restarts_the_message() {
        let from: SocketAddr = "127.0.0.1:5000".parse().unwrap();
        let now = Instant::now();
        let mut r = Reassembler::new(Limits::default());
        let a = encode_datagrams(3, "X", &vec![1u8; 100_000]).unwrap();
        let b = encode_datagrams(3, "X", &vec![2u8; 140_000]).unwrap();
        assert!(reassemble(&mut r, &a[..1], from, now).is_empty());
        let out = reassemble(&mut r, &b, from, now);
        assert_eq!(out[0].data, vec![2u8; 140_000]);
    }

    #[test]
    fn malformed_datagrams_are_refused() {
        assert_eq!(parse_datagram(b"LC02\0\0"), Err(BadPacket::Short));
        assert_eq!(parse_datagram(b"LC04\0\0\0\0X\0"), Err(BadPacket::Magic));
        assert_eq!(parse_datagram(b"LC02\0\0\0\0XYZ"), Err(BadPacket::Channel));
        let long_channel = [b"LC02\0\0\0\0".as_slice(), &[b'a'; 64], &[0]].concat();
        assert_eq!(parse_datagram(&long_channel), Err(BadPacket::Channel));
        let mut f = encode_datagrams(1, "X", &vec![0u8; 70_000]).unwrap().remove(1);
        assert_eq!(parse_datagram(&f[..19]), Err(BadPacket::Short));
        f[16..18].copy_from_slice(&2u16.to_be_bytes()); // number 2 of 2
        assert_eq!(parse_datagram(&f), Err(BadPacket::Fragment));
        f[16..18].copy_from_slice(&1u16.to_be_bytes());
        f[12..16].copy_from_slice(&69_000u32.to_be_bytes()); // data past the payload size
        assert_eq!(parse_datagram(&f), Err(BadPacket::Fragment));
        assert!(encode_datagrams(1, &"a".repeat(64), b"").is_err());
        assert!(encode_datagrams(1, "a\0b", b"").is_err());
    }

    proptest::proptest! {
        #[test]
        fn any_order_with_duplicates_reassembles_exactly(
            len in 0usize..300_000,
            channel in "[A-Za-z0-9_]{0,63}",
            order in proptest::collection::vec(proptest::prelude::any::<u16>(), 0..12),
            seq in proptest::prelude::any::<u32>(),
        ) {
            let payload: Vec<u8> = (0..len).map(|i| (i as u32).wrapping_mul(2_654_435_761).to_be_bytes()[0]).collect();
            let datagrams = encode_datagrams(seq, &channel, &payload).unwrap();
            let from: SocketAddr = "127.0.0.1:5000".parse().unwrap();
            if datagrams.len() == 1 {
                match parse_datagram(&datagrams[0]).unwrap() {
                    Packet::Short { seq: s, channel: c, payload: p } => {
                        proptest::prop_assert_eq!((s, c, p), (seq, channel.as_str(), payload.as_slice()));
                    }
                    Packet::Fragment(_) => proptest::prop_assert!(false, "a short message was fragmented"),
                }
            } else {
                // Some datagrams again first (duplicates), then all of them in reverse, then the
                // duplicates once more (late, after the message is complete).
                let dups: Vec<&Vec<u8>> = order.iter().map(|&k| &datagrams[usize::from(k) % datagrams.len()]).collect();
                let mut feed = dups.clone();
                feed.extend(datagrams.iter().rev());
                feed.extend(dups);
                let mut r = Reassembler::new(Limits::default());
                let now = Instant::now();
                let mut done = Vec::new();
                for d in feed {
                    let Packet::Fragment(f) = parse_datagram(d).unwrap() else { panic!("a fragment") };
                    done.extend(r.push(from, &f, now));
                }
                proptest::prop_assert_eq!(done, vec![Assembled { channel: channel.clone(), data: payload, seq }]);
                proptest::prop_assert_eq!(r.bytes_held(), 0);
            }
        }

        #[test]
        fn damaged_datagrams_never_panic_and_stay_in_bounds(
            len in 60_000usize..200_000,
            flips in proptest::collection::vec((proptest::prelude::any::<usize>(), proptest::prelude::any::<u8>()), 1..6),
            cut in proptest::prelude::any::<usize>(),
        ) {
            let payload = vec![9u8; len];
            let mut datagrams = encode_datagrams(4, "CH", &payload).unwrap();
            for (k, (at, byte)) in flips.into_iter().enumerate() {
                let n = datagrams.len();
                let d = &mut datagrams[k % 2 % n];
                let at = at % d.len();
                d[at] = byte;
            }
            let last = datagrams.len() - 1;
            let keep = cut % (datagrams[last].len() + 1);
            datagrams[last].truncate(keep);
            let limits = Limits { max_message_size: 150_000, max_partials: 3, max_partial_bytes: 300_000, stale_after: Duration::from_secs(1) };
            let mut r = Reassembler::new(limits);
            let from: SocketAddr = "127.0.0.1:5000".parse().unwrap();
            for d in &datagrams {
                if let Ok(Packet::Fragment(f)) = parse_datagram(d) {
                    if let Some(a) = r.push(from, &f, Instant::now()) {
                        proptest::prop_assert!(a.data.len() <= limits.max_message_size);
                    }
                }
                proptest::prop_assert!(r.partials() <= limits.max_partials);
                proptest::prop_assert!(r.bytes_held() <= limits.max_partial_bytes);
            }
        }
    }
}
