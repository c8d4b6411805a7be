//! The two files of a labelled stream: `<stem>.bin` (little-endian `i16` samples) and
//! `<stem>.truth.csv` (the truth of every impact, gap and fault), written and read back
//! (`FORMATS.md`).

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::sim::stream::{FaultEvent, FaultKind, Gap, ImpactFault, Stream, StreamError, Truth};

/// The two files of a stream: `<stem>.bin` (samples) and `<stem>.truth.csv` (truth). A path
/// ending in `.bin` names the same pair as the path without it.
pub fn stream_paths(out: &Path) -> (PathBuf, PathBuf) {
    let stem = if out.extension().is_some_and(|e| e == "bin") {
        out.with_extension("")
    } else {
        out.to_path_buf()
    };
    let with = |suffix: &str| {
        let mut s = stem.clone().into_os_string();
        s.push(suffix);
        PathBuf::from(s)
    };
    (with(".bin"), with(".truth.csv"))
}

/// One row of the truth file (see `FORMATS.md`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
struct Row {
    kind: String,
    id: Option<u64>,
    sample: Option<u64>,
    position: Option<u64>,
    length: Option<u64>,
    value: Option<f64>,
    class: Option<usize>,
    class_name: Option<String>,
    radius_m: Option<f64>,
    speed_m_s: Option<f64>,
    time_s: Option<f64>,
    peak_time_s: Option<f64>,
    peak_force_n: Option<f64>,
    duration_s: Option<f64>,
    fault: Option<String>,
}

/// Writes `<stem>.bin` (little-endian `i16`) and `<stem>.truth.csv`; returns both paths.
pub fn write_stream(stream: &Stream, out: &Path) -> Result<(PathBuf, PathBuf), StreamError> {
    let (bin, csv_path) = stream_paths(out);
    if let Some(dir) = bin.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    }
    let mut bytes = Vec::with_capacity(2 * stream.samples.len());
    for s in &stream.samples {
        bytes.extend_from_slice(&s.to_le_bytes());
    }
    std::fs::File::create(&bin)
        .and_then(|mut f| f.write_all(&bytes))
        .map_err(io_err(&bin))?;
    let header = Row {
        kind: "stream".into(),
        id: Some(0),
        sample: Some(stream.timeline_samples),
        position: Some(stream.samples.len() as u64),
        value: Some(stream.sample_rate_hz),
        time_s: Some(stream.phase_s),
        ..Row::default()
    };
    let classes: Vec<Row> = stream
        .class_names
        .iter()
        .enumerate()
        .map(|(i, name)| Row {
            kind: "class".into(),
            id: Some(i as u64),
            class: Some(i),
            class_name: Some(name.clone()),
            ..Row::default()
        })
        .collect();
    let rows = timed_rows(stream);
    let mut w = csv::Writer::from_path(&csv_path).map_err(|e| csv_err(&csv_path, e))?;
    for row in std::iter::once(&header)
        .chain(classes.iter())
        .chain(rows.iter().map(|(_, r)| r))
    {
        w.serialize(row).map_err(|e| csv_err(&csv_path, e))?;
    }
    w.flush().map_err(io_err(&csv_path))?;
    Ok((bin, csv_path))
}

/// The I/O error of `path`.
fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StreamError {
    let path = path.to_path_buf();
    move |error| StreamError::Io { path, error }
}

/// Stored position of the time-line index `at`, `None` when it was dropped or is past the
/// end.
fn stored_position(stream: &Stream, at: u64) -> Option<u64> {
    if at >= stream.timeline_samples {
        return None;
    }
    let mut lost = 0u64;
    for g in &stream.gaps {
        if g.at_sample > at {
            break;
        }
        if at < g.at_sample.saturating_add(g.lost as u64) {
            return None;
        }
        lost += g.lost as u64;
    }
    Some(at - lost)
}

/// The impact, gap, spike and stuck rows, by time-line sample.
fn timed_rows(stream: &Stream) -> Vec<(u64, Row)> {
    let fs = stream.sample_rate_hz;
    let mut rows: Vec<(u64, Row)> = Vec::new();
    for (i, t) in stream.truth.iter().enumerate() {
        rows.push((
            t.peak_sample,
            Row {
                kind: "impact".into(),
                id: Some(i as u64),
                sample: Some(t.peak_sample),
                position: stored_position(stream, t.peak_sample),
                length: Some((t.duration_s * fs).ceil() as u64),
                value: Some(t.scale),
                class: Some(t.class),
                class_name: stream.class_names.get(t.class).cloned(),
                radius_m: Some(t.radius_m),
                speed_m_s: Some(t.speed_m_s),
                time_s: Some(t.time_s),
                peak_time_s: Some(t.peak_time_s),
                peak_force_n: Some(t.peak_force_n),
                duration_s: Some(t.duration_s),
                fault: Some(t.fault.name().into()),
            },
        ));
    }
    for (i, g) in stream.gaps.iter().enumerate() {
        rows.push((
            g.at_sample,
            Row {
                kind: "gap".into(),
                id: Some(i as u64),
                sample: Some(g.at_sample),
                position: Some(g.position as u64),
                length: Some(g.lost as u64),
                ..Row::default()
            },
        ));
    }
    for (i, e) in stream.events.iter().enumerate() {
        rows.push((
            e.at_sample,
            Row {
                kind: match e.kind {
                    FaultKind::Spike => "spike".into(),
                    FaultKind::Stuck => "stuck".into(),
                },
                id: Some(i as u64),
                sample: Some(e.at_sample),
                position: stored_position(stream, e.at_sample),
                length: Some(e.length as u64),
                value: Some(e.value),
                ..Row::default()
            },
        ));
    }
    rows.sort_by_key(|(at, _)| *at);
    rows
}

fn csv_err(path: &Path, e: csv::Error) -> StreamError {
    StreamError::Format {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Checks the samples read from `bin` against the truth file: as many as its `stream` row's
/// `position` (stored samples), which is the time line less the gaps' lost samples.
fn check_length(
    stream: &Stream,
    stored: Option<u64>,
    bin: &Path,
    csv_path: &Path,
) -> Result<(), StreamError> {
    let stored = stored.unwrap_or(0);
    let lost: u64 = stream.gaps.iter().map(|g| g.lost as u64).sum();
    if stream.timeline_samples.checked_sub(lost) != Some(stored) {
        return Err(StreamError::Format {
            path: csv_path.to_path_buf(),
            message: format!(
                "the stream row's position ({stored} stored samples) is not its sample \
                 ({} samples in the time line) less the gaps' {lost} lost samples",
                stream.timeline_samples
            ),
        });
    }
    let read = stream.samples.len() as u64;
    if read != stored {
        return Err(StreamError::Format {
            path: bin.to_path_buf(),
            message: format!(
                "holds {read} samples, but the truth file's stream row (position) says {stored}: \
                 the samples are {}",
                if read < stored {
                    "truncated"
                } else {
                    "longer than the stream (doubled or appended?)"
                }
            ),
        });
    }
    Ok(())
}

/// Reads a stream written by [`write_stream`] (`out` as given to it); the samples must be as
/// many as the truth file says (see `FORMATS.md`).
pub fn read_stream(out: &Path) -> Result<Stream, StreamError> {
    let (bin, csv_path) = stream_paths(out);
    let samples = read_samples(&bin)?;
    let bad = |message: String| StreamError::Format {
        path: csv_path.clone(),
        message,
    };
    let mut rd = csv::Reader::from_path(&csv_path).map_err(|e| csv_err(&csv_path, e))?;
    let mut stream = Stream {
        sample_rate_hz: f64::NAN,
        phase_s: 0.0,
        class_names: Vec::new(),
        samples,
        timeline_samples: 0,
        truth: Vec::new(),
        gaps: Vec::new(),
        events: Vec::new(),
    };
    let mut stored_samples = None;
    for (line, row) in rd.deserialize::<Row>().enumerate() {
        let row = row.map_err(|e| csv_err(&csv_path, e))?;
        if let Some(stored) = read_row(&mut stream, &row, line + 2).map_err(bad)? {
            stored_samples = Some(stored);
        }
    }
    if !stream.sample_rate_hz.is_finite() {
        return Err(bad("no stream row".into()));
    }
    check_length(&stream, stored_samples, &bin, &csv_path)?;
    // Truth rows are written by peak time; the stream keeps them by first contact.
    stream.truth.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    stream.gaps.sort_by_key(|g| g.position);
    if stream
        .gaps
        .last()
        .is_some_and(|g| g.position > stream.samples.len())
    {
        return Err(bad("a gap lies past the end of the samples".into()));
    }
    Ok(stream)
}

/// The little-endian `i16` samples of `bin`.
fn read_samples(bin: &Path) -> Result<Vec<i16>, StreamError> {
    let mut bytes = Vec::new();
    std::fs::File::open(bin)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(io_err(bin))?;
    if bytes.len() % 2 != 0 {
        return Err(StreamError::Format {
            path: bin.to_path_buf(),
            message: "odd number of bytes: not a stream of i16 samples".into(),
        });
    }
    Ok(bytes
        .chunks_exact(2)
        .map(|c| i16::from_le_bytes([c[0], c[1]]))
        .collect())
}

/// Adds truth row `row` (line `line` of the file) to `stream`; for the `stream` row, returns
/// the stored samples it states. Errors name the line and the missing column.
fn read_row(stream: &mut Stream, row: &Row, line: usize) -> Result<Option<u64>, String> {
    let need = |name: &str, v: Option<f64>| {
        v.ok_or_else(|| format!("row {line}: {} row without {name}", row.kind))
    };
    let need_u = |name: &str, v: Option<u64>| need(name, v.map(|x| x as f64)).map(|x| x as u64);
    match row.kind.as_str() {
        "stream" => {
            stream.sample_rate_hz = need("value", row.value)?;
            stream.phase_s = need("time_s", row.time_s)?;
            stream.timeline_samples = need_u("sample", row.sample)?;
            return Ok(Some(need_u("position", row.position)?));
        }
        "class" => {
            let class = need_u("class", row.class.map(|c| c as u64))? as usize;
            if class != stream.class_names.len() {
                return Err(format!("row {line}: class rows out of order"));
            }
            stream
                .class_names
                .push(row.class_name.clone().unwrap_or_default());
        }
        "impact" => {
            let class = need_u("class", row.class.map(|c| c as u64))? as usize;
            let fault = row.fault.as_deref().unwrap_or("none");
            stream.truth.push(Truth {
                class,
                radius_m: need("radius_m", row.radius_m)?,
                speed_m_s: need("speed_m_s", row.speed_m_s)?,
                time_s: need("time_s", row.time_s)?,
                peak_time_s: need("peak_time_s", row.peak_time_s)?,
                peak_sample: need_u("sample", row.sample)?,
                peak_force_n: need("peak_force_n", row.peak_force_n)?,
                duration_s: need("duration_s", row.duration_s)?,
                scale: row.value.unwrap_or(1.0),
                fault: ImpactFault::from_name(fault)
                    .ok_or_else(|| format!("row {line}: unknown fault {fault:?}"))?,
            });
        }
        "gap" => stream.gaps.push(Gap {
            position: need_u("position", row.position)? as usize,
            at_sample: need_u("sample", row.sample)?,
            lost: need_u("length", row.length)?.min(u32::MAX as u64) as u32,
        }),
        "spike" | "stuck" => stream.events.push(FaultEvent {
            kind: if row.kind == "spike" {
                FaultKind::Spike
            } else {
                FaultKind::Stuck
            },
            at_sample: need_u("sample", row.sample)?,
            length: need_u("length", row.length)?.min(u32::MAX as u64) as u32,
            value: need("value", row.value)?,
        }),
        other => return Err(format!("row {line}: unknown kind {other:?}")),
    }
    Ok(None)
}
