//! What the firmware binaries of `coalshock-fw` and their host counterparts in host-sim
//! (`host-sim/examples/node_replay.rs`, `front_end.rs`) share: the replayed stream, the gaps
//! recorded in its truth file, the scene, the integer output lines, and the front-end check
//! (the IIS3DWB driver over a fake SPI sensor serving the stream, [`front_end`]).
//!
//! The stream is made by host-sim (`fw/stream.sh`): `fw/data/paper_stream.bin` holds the stored
//! samples (little-endian i16 ADC codes, dropped samples left out) and
//! `fw/data/paper_stream.truth.csv` the truth (host-sim/FORMATS.md). Of the truth the node needs
//! only the `gap` rows (where samples were dropped and how many); they are parsed at compile
//! time into [`GAPS`], so the CSV text takes no flash.
//!
//! A second stream, `fw/data/chain_stream.bin` and `.truth.csv`, comes from the chain scene
//! `scenes/piezo_chain.toml` (a tail beam with three modes under a piezo accelerometer); it is
//! [`CHAIN`] and its scene [`build_chain_scene`]. [`PAPER`] is the first stream in the same
//! form.
//!
//! With the feature `plasticity` (the kernel's `plasticity` on) a third stream,
//! `fw/data/yield_stream.bin` and `.truth.csv`, comes from the yielding scene
//! `scenes/paper_yield.toml` (the paper's classes with Thornton's elastic-plastic contact); it
//! is `YIELD` and its scene `build_yield_scene`. Without the feature neither is compiled.
//!
//! The scenes ([`scenes`]) are written by `host-sim export` from the scene files, so the node
//! builds exactly the kernel scene host-sim builds from each file.
#![no_std]

pub mod front_end;

/// The scenes the node runs, each made from its scene file by `host-sim export` (`fw/stream.sh`
/// regenerates them; `fw/stream.sh --check` fails unless they are reproduced byte for byte).
pub mod scenes {
    pub mod paper;
    #[cfg(feature = "plasticity")]
    pub mod paper_yield;
    pub mod piezo_chain;
}

use coalshock::math::Backend;
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{Counters, ParticleClass, Report, Scene, Side, Verdict};

/// The replayed stream: little-endian i16 samples, dropped samples left out.
pub static STREAM: &[u8] = include_bytes!("../../data/paper_stream.bin");

/// The stream's truth file (only read at compile time, see [`GAPS`]).
const TRUTH: &[u8] = include_bytes!("../../data/paper_stream.truth.csv");

/// Samples stored in [`STREAM`].
pub const STORED_SAMPLES: usize = STREAM_BYTES / 2;
const STREAM_BYTES: usize = include_bytes!("../../data/paper_stream.bin").len();

/// Dropped samples of the stream: feed `STREAM[..position]`, then `Monitor::gap(lost)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Gap {
    /// Index of the stored sample before which samples are missing.
    pub position: usize,
    /// Samples lost there.
    pub lost: u32,
}

/// Number of `gap` rows of the truth file.
const GAP_COUNT: usize = count_rows(TRUTH, b"gap,");

/// The `gap` rows of the truth file, in order (compile-time parse: a malformed file is a
/// build error).
pub const GAPS: [Gap; GAP_COUNT] = gap_rows(TRUTH, STORED_SAMPLES);

/// The chain scene's stream (`fw/stream.sh`): little-endian i16 samples, dropped samples left
/// out.
static CHAIN_BYTES: &[u8] = include_bytes!("../../data/chain_stream.bin");
const CHAIN_TRUTH: &[u8] = include_bytes!("../../data/chain_stream.truth.csv");
const CHAIN_STORED: usize = include_bytes!("../../data/chain_stream.bin").len() / 2;
const CHAIN_GAP_COUNT: usize = count_rows(CHAIN_TRUTH, b"gap,");
const CHAIN_GAPS: [Gap; CHAIN_GAP_COUNT] = gap_rows(CHAIN_TRUTH, CHAIN_STORED);

/// The yielding scene's stream (`fw/stream.sh`): little-endian i16 samples, dropped samples
/// left out (feature `plasticity`).
#[cfg(feature = "plasticity")]
static YIELD_BYTES: &[u8] = include_bytes!("../../data/yield_stream.bin");
#[cfg(feature = "plasticity")]
const YIELD_TRUTH: &[u8] = include_bytes!("../../data/yield_stream.truth.csv");
#[cfg(feature = "plasticity")]
const YIELD_STORED: usize = include_bytes!("../../data/yield_stream.bin").len() / 2;
#[cfg(feature = "plasticity")]
const YIELD_GAP_COUNT: usize = count_rows(YIELD_TRUTH, b"gap,");
#[cfg(feature = "plasticity")]
const YIELD_GAPS: [Gap; YIELD_GAP_COUNT] = gap_rows(YIELD_TRUTH, YIELD_STORED);

/// A replayed stream: its stored samples and the gaps of its truth file.
#[derive(Debug, Clone, Copy)]
pub struct Stream {
    /// Little-endian i16 samples, dropped samples left out.
    pub bytes: &'static [u8],
    /// Dropped samples, in order: feed the stored samples before `position`, then
    /// `Monitor::gap(lost)`.
    pub gaps: &'static [Gap],
}

/// The paper scene's stream (`fw/data/paper_stream.*`): [`STREAM`] and [`GAPS`].
pub static PAPER: Stream = Stream {
    bytes: STREAM,
    gaps: &GAPS,
};

/// The chain scene's stream (`fw/data/chain_stream.*`, from `scenes/piezo_chain.toml`).
pub static CHAIN: Stream = Stream {
    bytes: CHAIN_BYTES,
    gaps: &CHAIN_GAPS,
};

/// The yielding scene's stream (`fw/data/yield_stream.*`, from `scenes/paper_yield.toml`;
/// feature `plasticity`).
#[cfg(feature = "plasticity")]
pub static YIELD: Stream = Stream {
    bytes: YIELD_BYTES,
    gaps: &YIELD_GAPS,
};

impl Stream {
    /// Samples stored.
    pub fn stored_samples(&self) -> usize {
        self.bytes.len() / 2
    }

    /// Stored sample `i` (0 past the end).
    pub fn sample(&self, i: usize) -> i16 {
        let lo = self.bytes.get(2 * i).copied().unwrap_or(0);
        let hi = self.bytes.get(2 * i + 1).copied().unwrap_or(0);
        i16::from_le_bytes([lo, hi])
    }

    /// Every stored sample in order, with each recorded gap at its place.
    pub fn inputs(&self) -> impl Iterator<Item = Input> + 'static {
        let stream = *self;
        let mut position = 0usize;
        let mut gaps = stream.gaps.iter().peekable();
        core::iter::from_fn(move || {
            if let Some(g) = gaps.next_if(|g| g.position <= position) {
                return Some(Input::Gap(g.lost));
            }
            if position < stream.stored_samples() {
                position += 1;
                return Some(Input::Sample(stream.sample(position - 1) as i32));
            }
            None
        })
    }
}

/// Header of the truth file; `position` and `length` are columns 3 and 4 (from 0).
const TRUTH_HEADER: &[u8] = b"kind,id,sample,position,length,value,";

const fn starts_with(s: &[u8], at: usize, prefix: &[u8]) -> bool {
    if at + prefix.len() > s.len() {
        return false;
    }
    let mut i = 0;
    while i < prefix.len() {
        if s[at + i] != prefix[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// Index just past the end of the line starting at `at` (past its `\n`).
const fn next_line(s: &[u8], mut at: usize) -> usize {
    while at < s.len() && s[at] != b'\n' {
        at += 1;
    }
    if at < s.len() { at + 1 } else { at }
}

const fn count_rows(csv: &[u8], kind: &[u8]) -> usize {
    let mut n = 0;
    let mut at = 0;
    while at < csv.len() {
        if starts_with(csv, at, kind) {
            n += 1;
        }
        at = next_line(csv, at);
    }
    n
}

/// The unsigned decimal in column `col` of the line starting at `at`.
const fn column_u64(csv: &[u8], at: usize, col: usize) -> u64 {
    let mut i = at;
    let mut c = 0;
    while c < col {
        while csv[i] != b',' {
            assert!(csv[i] != b'\n', "truth file: row too short");
            i += 1;
        }
        i += 1;
        c += 1;
    }
    let mut v: u64 = 0;
    let mut digits = 0;
    while i < csv.len() && csv[i] >= b'0' && csv[i] <= b'9' {
        v = v * 10 + (csv[i] - b'0') as u64;
        i += 1;
        digits += 1;
    }
    assert!(
        digits > 0 && csv[i] == b',',
        "truth file: not an unsigned integer"
    );
    v
}

const fn gap_rows<const K: usize>(csv: &[u8], stored: usize) -> [Gap; K] {
    assert!(
        starts_with(csv, 0, TRUTH_HEADER),
        "truth file: unexpected header"
    );
    let mut out = [Gap {
        position: 0,
        lost: 0,
    }; K];
    let mut k = 0;
    let mut at = 0;
    while at < csv.len() {
        if starts_with(csv, at, b"gap,") {
            let position = column_u64(csv, at, 3) as usize;
            let lost = column_u64(csv, at, 4) as u32;
            assert!(position <= stored, "truth file: gap past the end");
            assert!(
                k == 0 || position >= out[k - 1].position,
                "truth file: gaps out of order"
            );
            out[k] = Gap { position, lost };
            k += 1;
        }
        at = next_line(csv, at);
    }
    out
}

/// Stored sample `i` of the stream (0 past the end).
pub fn sample(i: usize) -> i16 {
    PAPER.sample(i)
}

/// One step of the replay: a stored sample, or a recorded gap before the next one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// The next stored sample.
    Sample(i32),
    /// Samples dropped here (`Monitor::gap`).
    Gap(u32),
}

/// The stream as the node replays it: every stored sample in order, with each recorded gap
/// at its place.
pub fn inputs() -> impl Iterator<Item = Input> {
    PAPER.inputs()
}

/// The scene the node runs: the paper scene of `scenes/paper.toml` ([`scenes::paper`]), with
/// math backend `M`.
pub fn build_scene<M: Backend>() -> Result<Scene<DEFAULT_CLASSES, M>, coalshock::Error> {
    scenes::paper::scene()
}

/// The chain scene of `scenes/piezo_chain.toml` ([`scenes::piezo_chain`]) with math backend
/// `M`: the paper's classes, plate and sensor behind a tail beam with three modes and a piezo
/// accelerometer.
pub fn build_chain_scene<M: Backend>() -> Result<Scene<DEFAULT_CLASSES, M>, coalshock::Error> {
    scenes::piezo_chain::scene()
}

/// The yielding scene of `scenes/paper_yield.toml` ([`scenes::paper_yield`]) with math
/// backend `M`: the paper scene with a limiting contact pressure for each class (coal 30 MPa,
/// sandstone 130 MPa), whose envelopes follow Thornton's elastic-plastic contact (feature
/// `plasticity`).
#[cfg(feature = "plasticity")]
pub fn build_yield_scene<M: Backend>() -> Result<Scene<DEFAULT_CLASSES, M>, coalshock::Error> {
    scenes::paper_yield::scene()
}

/// One `pulse` line, in integers so host and node print the same text.
pub struct PulseLine<'a> {
    /// Sample index of the report.
    pub at: u64,
    /// `class`, `ambiguous`, `out[:sides]` or `rejected`.
    pub kind: &'static str,
    /// Class name, nearest class, or reject reason.
    pub who: &'a str,
    /// Posterior in parts per million (0 without one).
    pub posterior_ppm: u32,
    /// Peak force in mN (0 without a measurement).
    pub force_mn: u32,
    /// Contact duration in ns (0 without a measurement).
    pub duration_ns: u32,
}

/// Kind of an out-of-envelope pulse by where the nearest class would need its radius and
/// speed: `OUT_KINDS[radius][speed]` with below/inside/above as 0/1/2.
const OUT_KINDS: [[&str; 3]; 3] = [
    ["out:r_below,u_below", "out:r_below", "out:r_below,u_above"],
    ["out:u_below", "out", "out:u_above"],
    ["out:r_above,u_below", "out:r_above", "out:r_above,u_above"],
];

fn side_index(s: Side) -> usize {
    match s {
        Side::Below => 0,
        Side::Inside => 1,
        Side::Above => 2,
    }
}

impl<'a> PulseLine<'a> {
    /// The line of report `r` with the scene's `classes`.
    pub fn new(r: &Report, classes: &'a [ParticleClass]) -> Self {
        let name = |i: u8| classes.get(i as usize).map_or("?", |c| c.name.as_str());
        let ppm = |p: f32| (p * 1e6 + 0.5) as u32;
        let (kind, who, posterior_ppm) = match r.verdict {
            Verdict::Class { class, posterior } => ("class", name(class), ppm(posterior)),
            Verdict::Ambiguous { best, posterior } => ("ambiguous", name(best), ppm(posterior)),
            Verdict::OutOfEnvelope {
                nearest,
                radius,
                speed,
            } => {
                let kind = OUT_KINDS
                    .get(side_index(radius))
                    .and_then(|row| row.get(side_index(speed)))
                    .copied()
                    .unwrap_or("out");
                (kind, name(nearest), 0)
            }
            Verdict::Rejected(reason) => ("rejected", reason.name(), 0),
        };
        let (force_mn, duration_ns) = r.measurement.map_or((0, 0), |m| {
            (
                (m.peak_force_n * 1e3 + 0.5) as u32,
                (m.duration_s * 1e9 + 0.5) as u32,
            )
        });
        Self {
            at: r.at_sample,
            kind,
            who,
            posterior_ppm,
            force_mn,
            duration_ns,
        }
    }
}

/// Counter fields of the final `counters` line.
pub struct CounterLine {
    /// Samples fed.
    pub samples: u64,
    /// Pulses seen.
    pub pulses: u32,
    /// Ambiguous verdicts.
    pub ambiguous: u32,
    /// Out-of-envelope verdicts.
    pub out: u32,
    /// Rejected pulses, all reasons.
    pub rejected: u32,
    /// Stuck runs.
    pub stuck: u32,
    /// Gaps reported.
    pub gaps: u32,
    /// Samples lost in gaps.
    pub lost: u64,
    /// 1 when every pulse was counted once.
    pub balanced: u32,
}

impl CounterLine {
    /// The line of counters `c`.
    pub fn new(c: &Counters<DEFAULT_CLASSES>) -> Self {
        Self {
            samples: c.samples,
            pulses: c.pulses,
            ambiguous: c.ambiguous,
            out: c.out_of_envelope,
            rejected: c.rejected.iter().sum(),
            stuck: c.stuck_runs,
            gaps: c.gaps,
            lost: c.lost_samples,
            balanced: c.balanced() as u32,
        }
    }
}
