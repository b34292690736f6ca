//! Request streams in Ramulator's DRAM-trace format, and a driver that feeds one to [`Dram`]
//! the way Ramulator's `--mode=dram` does (docs/cycle-model.md, "DRAM model against Ramulator").
//!
//! # Format
//! One request per line: a hexadecimal byte address (optional leading blanks, optional `0x`),
//! one separator character, then the first non-blank character decides the type: `R` or nothing
//! is a read, `W` a write (Ramulator's `Trace::get_dramtrace_request`). Anything else is an
//! error naming the file and the line.
//!
//! # Feeding semantics (Ramulator's `run_dramtrace`)
//! - requests enter in file order, at most one per DRAM clock;
//! - a request waits while its channel's queue of its type holds `read_queue` (reads) or
//!   `write_queue` (writes) requests, and nothing behind it enters meanwhile (head-of-line
//!   blocking across channels); a read leaves its queue at its activate (or its read command if
//!   its row is open), a write at its write command;
//! - a read of a line whose write is still in the write queue is answered one clock later from
//!   that write (Ramulator's enqueue shortcut);
//! - after the last request the posted writes are drained; the run ends when the last read's
//!   data has returned and the last write command has issued;
//! - a read's latency runs from its entry to its data return; bandwidth is all bytes moved
//!   over the run's time.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::config::DramConfig;
use crate::dram::{Dram, Ps, Ticket};

/// One request of a stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamRequest {
    /// Byte address.
    pub addr: u64,
    /// A write (else a read).
    pub write: bool,
}

/// A malformed stream: the file, the 1-based line (0 when the file cannot be read) and why.
pub type StreamError = crate::file_error::LineError;

/// Parses one line (without its newline).
pub fn parse_line(line: &str) -> Result<StreamRequest, String> {
    let s = line.trim_start_matches([' ', '\t']);
    let digits = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")).unwrap_or(s);
    let n = digits.bytes().take_while(u8::is_ascii_hexdigit).count();
    if n == 0 {
        return Err(format!("expected a hexadecimal address, found {:?}", truncate(line)));
    }
    let addr = u64::from_str_radix(&digits[..n], 16)
        .map_err(|_| format!("address {} does not fit in 64 bits", &digits[..n]))?;
    // One separator after the address, then the first non-blank character decides the type.
    let rest = &digits[n..];
    let mut chars = rest.chars();
    chars.next();
    let write = match chars.as_str().trim_start_matches(' ').chars().next() {
        None | Some('R') => false,
        Some('W') => true,
        Some(c) => return Err(format!("request type {c:?}: expected R or W")),
    };
    Ok(StreamRequest { addr, write })
}

fn truncate(s: &str) -> String {
    s.chars().take(40).collect()
}

/// Parses a whole stream, at least one request; `path` names it in errors.
pub fn parse_stream(text: &str, path: &Path) -> Result<Vec<StreamRequest>, StreamError> {
    let mut out = Vec::with_capacity(text.len() / 13);
    for (i, line) in text.lines().enumerate() {
        let req = parse_line(line).map_err(|message| StreamError {
            path: path.to_path_buf(),
            line: i + 1,
            message,
        })?;
        out.push(req);
    }
    if out.is_empty() {
        return Err(StreamError {
            path: path.to_path_buf(),
            line: 0,
            message: "no requests: the stream is empty".into(),
        });
    }
    Ok(out)
}

/// Reads and parses a stream file.
pub fn read_stream(path: &Path) -> Result<Vec<StreamRequest>, StreamError> {
    let text = std::fs::read_to_string(path).map_err(|e| StreamError {
        path: path.to_path_buf(),
        line: 0,
        message: e.to_string(),
    })?;
    parse_stream(&text, path)
}

/// Checks that every request of `reqs` (the stream `path`, one request a line) lies in the
/// address space of the DRAM of `cfg` ([`Dram::address_space`]); the first that does not is an
/// error naming its line.
pub fn check_addresses(cfg: &DramConfig, reqs: &[StreamRequest], path: &Path) -> Result<(), StreamError> {
    let space = Dram::new(cfg).address_space();
    match reqs.iter().position(|r| r.addr as u128 >= space) {
        None => Ok(()),
        Some(i) => Err(StreamError {
            path: path.to_path_buf(),
            line: i + 1,
            message: format!(
                "address {:#x} is beyond the address space of DRAM '{}' ({space:#x} bytes)",
                reqs[i].addr, cfg.name
            ),
        }),
    }
}

/// The figures of one stream run, in Ramulator's terms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StreamRun {
    /// Requests.
    pub requests: u64,
    /// Reads.
    pub reads: u64,
    /// Writes.
    pub writes: u64,
    /// DRAM clocks from the first request's entry to the end (Ramulator's `dram_cycles`).
    pub dram_cycles: u64,
    /// Bytes moved (`line_bytes` per request).
    pub bytes: u64,
    /// Bytes per nanosecond over the run (GB/s, GB = 1e9 B).
    pub bandwidth_gbs: f64,
    /// Mean read latency from entry to data return, in DRAM clocks (`None` without reads).
    pub read_latency_avg_cycles: Option<f64>,
    /// The same in nanoseconds.
    pub read_latency_avg_ns: Option<f64>,
    /// Requests that found their row open.
    pub row_hits: u64,
    /// Requests that found their bank closed.
    pub row_misses: u64,
    /// Requests that found another row open.
    pub row_conflicts: u64,
}

impl StreamRun {
    /// Row hits over requests.
    pub fn row_hit_rate(&self) -> f64 {
        crate::dram::row_hit_rate(self.row_hits, self.row_misses, self.row_conflicts)
    }
}

/// The DRAM model behind Ramulator's request queues: a request enters its channel's read or
/// write queue only while that queue has room (`read_queue`, `write_queue` entries; a read
/// leaves the read queue at its activate, or at its read command if its row is open, a write
/// leaves at its write command). Callers ask for room, then submit.
pub struct QueueFeeder {
    /// The DRAM model.
    pub dram: Dram,
    rcap: usize,
    wcap: usize,
    ck: Ps,
}

impl QueueFeeder {
    /// A fresh DRAM of `cfg` behind empty queues.
    pub fn new(cfg: &DramConfig) -> Self {
        QueueFeeder {
            dram: Dram::new(cfg),
            rcap: cfg.read_queue.max(1) as usize,
            wcap: cfg.write_queue as usize,
            ck: cfg.t_ck_ps,
        }
    }

    /// The channel of `addr`.
    pub fn channel(&self, addr: u64) -> usize {
        self.dram.map(addr).0
    }

    /// The latest write command so far (a write is done at its command).
    pub fn write_end(&self) -> Ps {
        self.dram.last_write_command()
    }

    /// `Ok` when channel `c`'s read queue has room at `t`; else the first time it has.
    pub fn read_room(&mut self, t: Ps, c: usize) -> Result<(), Ps> {
        let cap = self.rcap;
        self.room(t, c, move |d: &Dram| d.read_queue_len(c) < cap)
    }

    /// `Ok` when channel `c`'s write queue has room at `t`; else the first time it has.
    pub fn write_room(&mut self, t: Ps, c: usize) -> Result<(), Ps> {
        let cap = self.wcap;
        self.room(t, c, move |d: &Dram| d.write_queue_len(c) < cap)
    }

    /// `Ok` when `has_room` at `t`; else the next time channel `c` can change (the channel is
    /// never advanced past `t`, so requests of other channels' or other lists still to come at
    /// times before that enter in order).
    fn room(&mut self, t: Ps, c: usize, has_room: impl Fn(&Dram) -> bool) -> Result<(), Ps> {
        self.dram.advance_to(c, t);
        if has_room(&self.dram) {
            return Ok(());
        }
        Err(self.dram.next_change(c).max(t + 1))
    }

    /// Queues a read of `addr` at `t` (after [`QueueFeeder::read_room`] said yes). A read of a
    /// line with a write still in the write queue is answered one clock later from that write,
    /// as Ramulator's controller does on enqueue.
    pub fn submit_read(&mut self, t: Ps, addr: u64) -> Ticket {
        self.dram.advance_to(self.channel(addr), t);
        if self.dram.write_queued(addr) {
            return self.dram.forwarded_read(t + self.ck);
        }
        self.dram.submit_read(t, addr)
    }

    /// Posts a write of `addr` at `t` (after [`QueueFeeder::write_room`] said yes).
    pub fn write(&mut self, t: Ps, addr: u64) {
        self.dram.write(t, addr);
    }

    /// Serves every queued read and drains every write at `last`.
    pub fn flush(&mut self, last: Ps) {
        self.dram.flush(last);
    }
}

/// Runs `reqs` through the DRAM model of `cfg` under Ramulator's trace-mode feeding semantics.
pub fn run_stream(cfg: &DramConfig, reqs: &[StreamRequest]) -> StreamRun {
    let ck = cfg.t_ck_ps;
    let mut f = QueueFeeder::new(cfg);
    let mut t: Ps = 0;
    let mut all_reads: Vec<Ticket> = Vec::new();
    for r in reqs {
        let c = f.channel(r.addr);
        loop {
            let room = if r.write { f.write_room(t, c) } else { f.read_room(t, c) };
            match room {
                Ok(()) => break,
                Err(next) => t = next,
            }
        }
        if r.write {
            f.write(t, r.addr);
        } else {
            all_reads.push(f.submit_read(t, r.addr));
        }
        // The next request enters one clock later at the earliest.
        t = (t / ck + 1) * ck;
    }
    let mut end = 0;
    for k in all_reads {
        end = end.max(f.dram.arrival(k));
    }
    f.flush(t);
    end = end.max(f.write_end());
    let s = f.dram.stats();
    let n = reqs.len() as u64;
    let bytes = n * cfg.line_bytes as u64;
    let dram_cycles = end.div_ceil(ck).max(1);
    let time_ns = dram_cycles as f64 * ck as f64 / 1000.0;
    let lat_ns = (s.reads > 0).then(|| s.read_latency_ps as f64 / s.reads as f64 / 1000.0);
    StreamRun {
        requests: n,
        reads: s.reads,
        writes: s.writes,
        dram_cycles,
        bytes,
        bandwidth_gbs: bytes as f64 / time_ns,
        read_latency_avg_cycles: lat_ns.map(|l| l * 1000.0 / ck as f64),
        read_latency_avg_ns: lat_ns,
        row_hits: s.row_hits,
        row_misses: s.row_misses,
        row_conflicts: s.row_conflicts,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The last line of the address space is served (its row is below the closed-bank marker);
    /// the first address past it is an error naming its line, before any run.
    #[test]
    fn addresses_are_checked_against_the_address_space() {
        let cfg = DramConfig::default();
        let space = Dram::new(&cfg).address_space();
        let line = cfg.line_bytes as u64;
        let last = (space - line as u128) as u64;
        let path = Path::new("s.trace");
        let ok = [StreamRequest { addr: 0, write: false }, StreamRequest { addr: last, write: false }];
        assert_eq!(check_addresses(&cfg, &ok, path), Ok(()));
        let run = run_stream(&cfg, &ok);
        assert_eq!((run.reads, run.row_misses), (2, 2));
        let bad = [ok[0], StreamRequest { addr: last + line, write: true }];
        let err = check_addresses(&cfg, &bad, path).unwrap_err();
        assert_eq!((err.line, err.path.as_path()), (2, path));
        assert!(err.message.contains(&format!("{:#x}", last + line)), "{}", err.message);
    }

    #[test]
    fn lines_follow_ramulators_reading_rules() {
        let r = |s: &str| parse_line(s).unwrap();
        assert_eq!(r("0x00000040 R"), StreamRequest { addr: 64, write: false });
        assert_eq!(r("0x10000000 W"), StreamRequest { addr: 1 << 28, write: true });
        assert_eq!(r("ff"), StreamRequest { addr: 255, write: false });
        assert_eq!(r("0x80 "), StreamRequest { addr: 128, write: false });
        assert_eq!(r("0x80    W"), StreamRequest { addr: 128, write: true });
        assert_eq!(r("  0X80,W"), StreamRequest { addr: 128, write: true });
        assert!(parse_line("").unwrap_err().contains("hexadecimal"));
        assert!(parse_line("R 0x40").unwrap_err().contains("hexadecimal"));
        assert!(parse_line("0x40 X").unwrap_err().contains("expected R or W"));
        assert!(parse_line("0x1ffffffffffffffff R").unwrap_err().contains("64 bits"));
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let e = parse_stream("0x0 R\n0x40 W\nzz\n", Path::new("s.trace")).unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.to_string().starts_with("s.trace:3: "), "{e}");
        let e = parse_stream("", Path::new("e.trace")).unwrap_err();
        assert!(e.to_string().starts_with("e.trace: no requests"), "{e}");
    }

    #[test]
    fn a_read_of_a_queued_write_is_answered_from_it() {
        let cfg = DramConfig::default();
        // A read waiting on channel 0 keeps its 4 writes posted (no drain below 80% full).
        let mut f = QueueFeeder::new(&cfg);
        let _other = f.submit_read(0, 100 * 256);
        for i in 0..4 {
            f.write(0, i * 256);
        }
        let k = f.submit_read(1000, 2 * 256);
        assert_eq!(f.dram.scheduled(k), Some(1000 + cfg.t_ck_ps));
        assert_eq!(f.dram.stats().forwarded, 1);
        // A line not written goes to the DRAM.
        let k = f.submit_read(1000, 9 * 256);
        assert!(f.dram.arrival(k) > 1000 + 20 * cfg.t_ck_ps);
        assert_eq!(f.dram.stats().forwarded, 1);
    }

    #[test]
    fn reads_enter_one_per_clock_and_wait_for_a_full_queue() {
        let cfg = DramConfig::default();
        // 4 reads, one per channel, of closed banks: each activates on the clock after its
        // entry, then takes RCD + CL + DQSCK + BL.
        let reqs: Vec<_> = (0..4).map(|i| StreamRequest { addr: i * 64, write: false }).collect();
        let run = run_stream(&cfg, &reqs);
        let miss = 1 + cfg.n_rcd + cfg.n_cl + cfg.n_dqsck + cfg.n_bl;
        assert_eq!(run.row_misses, 4);
        // The last enters at clock 3 and is not slowed by the others (other channels).
        assert_eq!(run.dram_cycles, 3 + miss);
        assert_eq!(run.read_latency_avg_cycles, Some(miss as f64));
        // 64 reads of one channel's open row: the 32-entry queue fills, so later reads wait
        // to enter, and one burst per BL clocks leaves.
        let reqs: Vec<_> = (0..64).map(|i| StreamRequest { addr: i * 256, write: false }).collect();
        let run = run_stream(&cfg, &reqs);
        assert_eq!(run.row_hits, 63);
        let bus = 64 * cfg.n_bl;
        assert!(run.dram_cycles >= bus && run.dram_cycles < bus + miss + 8, "{run:?}");
    }
}
