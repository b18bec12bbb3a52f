//! LCM log files as lcm-logger writes them: a [`LogWriter`] and a resynchronising [`LogReader`].
//!
//! The format, restated from lcm-proj/lcm's `docs/content/log-file-format.md` and `lcm/eventlog.c`:
//! the file is a sequence of events, each a 28-byte big-endian header, the sync word `0xEDA1DA01`,
//! an `int64` event number (from 0, one more each event), an `int64` timestamp (microseconds since
//! the epoch), an `int32` channel length and an `int32` data length, followed by the channel's
//! UTF-8 bytes (no NUL) and the data. lcm's reader scans byte by byte for the sync word and takes
//! a channel length only in `1..1000`, a data length only if not negative.
//!
//! This reader does the same, and bounds the data length too (by [`LogReader::with_max_data`],
//! 2^28 bytes by default); an event whose header is out of bounds is skipped by resuming the scan
//! one byte after its sync word, so a damaged stretch costs only the events in it. Lengths are
//! never allocated up front: the bytes are read as they come, so a lying header on a truncated
//! file costs only the bytes really there.

use std::io::{self, BufRead, BufReader, Read, Write};

use crate::error::LogError;

/// The word each event starts with.
pub const SYNC_WORD: u32 = 0xEDA1_DA01;
/// The header's length.
pub const HEADER_LEN: usize = 28;
/// lcm's bound on a channel length (exclusive).
pub const MAX_CHANNEL_LEN: usize = 1000;

/// One logged message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Event {
    pub event_number: i64,
    /// Microseconds since the epoch.
    pub timestamp: i64,
    pub channel: String,
    pub data: Vec<u8>,
}

/// Writes events, numbering them from 0.
#[derive(Debug)]
pub struct LogWriter<W: Write> {
    out: W,
    next: i64,
}

impl<W: Write> LogWriter<W> {
    /// A writer onto `out` (wrap a file in a `BufWriter`).
    pub fn new(out: W) -> Self {
        Self { out, next: 0 }
    }

    /// Writes one event with the next event number; returns that number.
    pub fn write(&mut self, timestamp: i64, channel: &str, data: &[u8]) -> Result<i64, LogError> {
        let too_large = || LogError::TooLarge { channel_len: channel.len(), data_len: data.len() };
        if channel.is_empty() || channel.len() >= MAX_CHANNEL_LEN {
            return Err(too_large());
        }
        let data_len = i32::try_from(data.len()).map_err(|_| too_large())?;
        let mut header = [0u8; HEADER_LEN];
        header[..4].copy_from_slice(&SYNC_WORD.to_be_bytes());
        header[4..12].copy_from_slice(&self.next.to_be_bytes());
        header[12..20].copy_from_slice(&timestamp.to_be_bytes());
        header[20..24].copy_from_slice(&(channel.len() as i32).to_be_bytes());
        header[24..28].copy_from_slice(&data_len.to_be_bytes());
        self.out.write_all(&header)?;
        self.out.write_all(channel.as_bytes())?;
        self.out.write_all(data)?;
        self.next += 1;
        Ok(self.next - 1)
    }

    /// Flushes and hands back the output.
    pub fn into_inner(mut self) -> Result<W, LogError> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Reads events, resynchronising on the sync word.
#[derive(Debug)]
pub struct LogReader<R: Read> {
    input: BufReader<R>,
    /// Bytes read but to be scanned again (after a header out of bounds), oldest first.
    pushback: Vec<u8>,
    offset: u64,
    max_data: usize,
    skipped: u64,
}

impl<R: Read> LogReader<R> {
    /// A reader of `input`.
    pub fn new(input: R) -> Self {
        Self { input: BufReader::new(input), pushback: Vec::new(), offset: 0, max_data: 1 << 28, skipped: 0 }
    }

    /// The reader with another bound on an event's data length.
    #[must_use]
    pub fn with_max_data(mut self, max_data: usize) -> Self {
        self.max_data = max_data;
        self
    }

    /// Bytes passed over while looking for a sync word, or in events refused for their lengths.
    pub fn skipped_bytes(&self) -> u64 {
        self.skipped
    }

    fn byte(&mut self) -> io::Result<Option<u8>> {
        if let Some(b) = self.pushback.pop() {
            self.offset += 1;
            return Ok(Some(b));
        }
        let buf = self.input.fill_buf()?;
        let Some(&b) = buf.first() else { return Ok(None) };
        self.input.consume(1);
        self.offset += 1;
        Ok(Some(b))
    }

    /// Fills `out` fully, or returns how many bytes there were.
    fn fill(&mut self, out: &mut [u8]) -> io::Result<usize> {
        for (i, slot) in out.iter_mut().enumerate() {
            match self.byte()? {
                Some(b) => *slot = b,
                None => return Ok(i),
            }
        }
        Ok(out.len())
    }

    /// Reads `n` bytes without allocating them up front.
    fn bytes(&mut self, n: usize) -> io::Result<Vec<u8>> {
        // Room for what a lying length could claim is reserved only up to 64 KiB.
        let mut out = Vec::with_capacity(n.min(1 << 16));
        while out.len() < n && !self.pushback.is_empty() {
            out.push(self.byte()?.expect("pushback is not empty"));
        }
        let want = (n - out.len()) as u64;
        let got = (&mut self.input).take(want).read_to_end(&mut out)?;
        self.offset += got as u64;
        Ok(out)
    }

    /// The next event; `None` at the end of the file (also when it ends before a sync word).
    pub fn read_event(&mut self) -> Result<Option<Event>, LogError> {
        loop {
            // Scan for the sync word.
            let mut word = 0u32;
            let mut seen = 0u32;
            let start = loop {
                let Some(b) = self.byte()? else {
                    self.skipped += u64::from(seen.min(4));
                    return Ok(None);
                };
                word = (word << 8) | u32::from(b);
                seen += 1;
                if seen >= 4 && word == SYNC_WORD {
                    self.skipped += u64::from(seen - 4);
                    break self.offset - 4;
                }
            };
            let mut header = [0u8; HEADER_LEN - 4];
            let got = self.fill(&mut header)?;
            if got < header.len() {
                return Err(LogError::Truncated { offset: start });
            }
            let event_number = i64::from_be_bytes(header[0..8].try_into().expect("8 bytes"));
            let timestamp = i64::from_be_bytes(header[8..16].try_into().expect("8 bytes"));
            let channel_len = i32::from_be_bytes(header[16..20].try_into().expect("4 bytes"));
            let data_len = i32::from_be_bytes(header[20..24].try_into().expect("4 bytes"));
            let sane = (1..MAX_CHANNEL_LEN as i32).contains(&channel_len)
                && data_len >= 0
                && data_len as usize <= self.max_data;
            if !sane {
                // Not an event after all (or a damaged one): scan again from the byte after its
                // sync word.
                self.offset -= header.len() as u64;
                self.pushback.extend(header.iter().rev());
                self.skipped += 4;
                continue;
            }
            let channel = self.bytes(channel_len as usize)?;
            let data = self.bytes(data_len as usize)?;
            if channel.len() < channel_len as usize || data.len() < data_len as usize {
                return Err(LogError::Truncated { offset: start });
            }
            let channel = String::from_utf8(channel).map_err(|_| LogError::BadChannel { offset: start })?;
            return Ok(Some(Event { event_number, timestamp, channel, data }));
        }
    }
}

impl<R: Read> Iterator for LogReader<R> {
    type Item = Result<Event, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.read_event().transpose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log_of(events: &[(i64, &str, &[u8])]) -> Vec<u8> {
        let mut w = LogWriter::new(Vec::new());
        for &(t, c, d) in events {
            w.write(t, c, d).unwrap();
        }
        w.into_inner().unwrap()
    }

    fn read_all(bytes: &[u8]) -> Vec<Event> {
        LogReader::new(bytes).collect::<Result<_, _>>().unwrap()
    }

    #[test]
    fn header_layout_follows_the_spec() {
        let bytes = log_of(&[(0x0102_0304_0506_0708, "AB", &[9, 8, 7])]);
        let mut want = vec![0xED, 0xA1, 0xDA, 0x01, 0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8];
        want.extend([0, 0, 0, 2, 0, 0, 0, 3, b'A', b'B', 9, 8, 7]);
        assert_eq!(bytes, want);
    }

    #[test]
    fn events_round_trip_with_their_numbers() {
        let bytes = log_of(&[(10, "A", b"one"), (20, "BB", b""), (30, "A", &[0; 5000])]);
        let events = read_all(&bytes);
        assert_eq!(events.len(), 3);
        assert_eq!(events.iter().map(|e| e.event_number).collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!((events[1].timestamp, events[1].channel.as_str(), events[1].data.len()), (20, "BB", 0));
        assert_eq!(events[2].data, vec![0; 5000]);
    }

    #[test]
    fn reader_resyncs_past_garbage_and_bad_headers() {
        let good = log_of(&[(1, "A", b"x"), (2, "B", b"y")]);
        let second = good.iter().skip(4).position(|&b| b == 0xED).unwrap() + 4;
        // Garbage before, a false sync word with a bad channel length, then the second event.
        let mut bytes = vec![1, 2, 3, 0xED, 0xA1];
        bytes.extend_from_slice(&good[..second]);
        bytes.extend_from_slice(&SYNC_WORD.to_be_bytes());
        bytes.extend_from_slice(&[0; 16]);
        bytes.extend_from_slice(&(-1i32).to_be_bytes());
        bytes.extend_from_slice(&[0; 4]);
        bytes.extend_from_slice(&good[second..]);
        let mut r = LogReader::new(bytes.as_slice());
        let events: Vec<Event> = r.by_ref().collect::<Result<_, _>>().unwrap();
        assert_eq!(events.iter().map(|e| e.channel.as_str()).collect::<Vec<_>>(), ["A", "B"]);
        assert!(r.skipped_bytes() >= 5 + 4);
    }

    #[test]
    fn sync_word_inside_a_refused_header_is_found() {
        // A false header whose own bytes hold the real event's start.
        let good = log_of(&[(7, "C", b"z")]);
        let mut bytes = SYNC_WORD.to_be_bytes().to_vec();
        bytes.extend_from_slice(&[0xFF; 3]);
        bytes.extend_from_slice(&good);
        let events = read_all(&bytes);
        assert_eq!(events.len(), 1);
        assert_eq!(events[0].timestamp, 7);
    }

    #[test]
    fn truncated_and_oversized_events_are_refused() {
        let bytes = log_of(&[(1, "A", &[1; 100])]);
        let mut r = LogReader::new(&bytes[..bytes.len() - 1]);
        assert!(matches!(r.read_event(), Err(LogError::Truncated { offset: 0 })));
        let mut r = LogReader::new(&bytes[..10]);
        assert!(matches!(r.read_event(), Err(LogError::Truncated { offset: 0 })));
        // A data length over the bound is not an event: nothing is read, nothing allocated.
        let mut r = LogReader::new(bytes.as_slice()).with_max_data(99);
        assert!(r.read_event().unwrap().is_none());
        // A header claiming 2^31-1 bytes on a short file is truncated, not allocated.
        let mut lying = bytes[..24].to_vec();
        lying.extend_from_slice(&i32::MAX.to_be_bytes());
        lying.extend_from_slice(b"A");
        let mut r = LogReader::new(lying.as_slice()).with_max_data(usize::MAX);
        assert!(matches!(r.read_event(), Err(LogError::Truncated { .. })));
        assert!(LogWriter::new(Vec::new()).write(0, "", b"").is_err());
        assert!(LogWriter::new(Vec::new()).write(0, &"c".repeat(1000), b"").is_err());
    }
}
