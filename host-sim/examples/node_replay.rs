//! The host half of the node check: host-sim reads the replayed stream (`fw/data/
//! paper_stream.bin` and `.truth.csv`) and replays it through the same kernel, printing the
//! `pulse`/`stuck`/`classified`/`rejected`/`counters` lines the node binary of `coalshock-fw`
//! prints, which `fw/ci.sh` compares with the emulated node's line by line, plus a `truth`
//! line (host only: the verdicts against the stream's truth). Then the same for the chain
//! scene's stream (`fw/data/chain_stream.*`, from `scenes/piezo_chain.toml`), every line
//! after the prefix `chain `. The kernel scene the node builds for each stream
//! (`fw/replay/src/scenes/`, written by `host-sim export`) must equal what host-sim makes of
//! its scene file (`scenes/paper.toml`, `scenes/piezo_chain.toml`). Then the yielding
//! scene's stream (`fw/data/yield_stream.*`, from `scenes/paper_yield.toml`), every line after
//! the prefix `yield `, which the node built with the feature `plasticity` prints.
//!
//! Run: `cargo run -p host-sim --example node_replay`.

use coalshock::RejectReason;
use coalshock::math::DefaultBackend;
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{Event, Monitor, ParticleClass, Scene, Verdict};
use coalshock_replay::{CounterLine, PulseLine, Stream};
use host_sim::replay::{match_truth, replay_events};
use host_sim::stream::ImpactFault;
use host_sim::stream_file::read_stream;

fn fail(what: String) -> ! {
    eprintln!("error {what}");
    std::process::exit(1)
}

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = coalshock_replay::build_scene::<DefaultBackend>()
        .unwrap_or_else(|e| fail(format!("scene {e:?}")));
    same_as_file(&scene, &root.join("scenes/paper.toml"), "paper scene");
    replay(
        "",
        &root.join("fw/data/paper_stream"),
        &coalshock_replay::PAPER,
        scene,
    );

    let chain = coalshock_replay::build_chain_scene::<DefaultBackend>()
        .unwrap_or_else(|e| fail(format!("chain scene {e:?}")));
    same_as_file(&chain, &root.join("scenes/piezo_chain.toml"), "chain scene");
    replay(
        "chain ",
        &root.join("fw/data/chain_stream"),
        &coalshock_replay::CHAIN,
        chain,
    );

    let yielding = coalshock_replay::build_yield_scene::<DefaultBackend>()
        .unwrap_or_else(|e| fail(format!("yield scene {e:?}")));
    same_as_file(
        &yielding,
        &root.join("scenes/paper_yield.toml"),
        "yield scene",
    );
    replay(
        "yield ",
        &root.join("fw/data/yield_stream"),
        &coalshock_replay::YIELD,
        yielding,
    );
}

/// The kernel scene the node builds (`fw/replay/src/scenes/`, written by `host-sim export`)
/// must equal what host-sim makes of the scene file.
fn same_as_file(node: &Scene<DEFAULT_CLASSES, DefaultBackend>, file: &std::path::Path, what: &str) {
    let from_file = host_sim::scene::load(file)
        .map_err(|e| format!("{e}"))
        .and_then(|f| host_sim::kernel_scene::scene_to_kernel(&f).map_err(|e| format!("{e:?}")))
        .unwrap_or_else(|e| fail(format!("{what} file {e}")));
    if &from_file != node {
        let name = file
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        fail(format!(
            "{what}: the node's scene differs from scenes/{name}'s"
        ));
    }
}

/// The host replay of one stream: host-sim reads the `.bin` + `.truth.csv` pair at `stem` and
/// replays it through the same kernel (`host_sim::replay::replay_events`: blocks through
/// `Monitor::feed_slice`, `Monitor::gap` at every recorded gap, `Monitor::finish`), and the
/// node's lines are printed after `prefix`. `node_stream` is the node's compiled-in copy.
/// The same stream fed one `Monitor::feed` per sample must give the same events; when it does
/// not, a `feed_check` line says where they part and the run fails.
fn replay(
    prefix: &str,
    stem: &std::path::Path,
    node_stream: &Stream,
    scene: Scene<DEFAULT_CLASSES, DefaultBackend>,
) {
    let stream = read_stream(stem).unwrap_or_else(|e| fail(format!("stream {e}")));
    // The node's copy of the stream (compiled in) must be what host-sim reads.
    let stored: Vec<i16> = (0..node_stream.stored_samples())
        .map(|i| node_stream.sample(i))
        .collect();
    if stream.samples != stored {
        fail("stream: the samples host-sim reads differ from the node's".into());
    }
    let gaps: Vec<(usize, u32)> = stream.gaps.iter().map(|g| (g.position, g.lost)).collect();
    let node_gaps: Vec<(usize, u32)> = node_stream
        .gaps
        .iter()
        .map(|g| (g.position, g.lost))
        .collect();
    if gaps != node_gaps {
        fail(format!(
            "stream: host-sim reads the gaps {gaps:?}, the node {node_gaps:?}"
        ));
    }

    let mut monitor = Monitor::new(scene);
    let events = replay_events(&stream, &mut monitor);
    // The node's own replay (one `feed` per sample, `gap` at the recorded gaps) must give the
    // same events as host-sim's (blocks through `feed_slice`).
    let mut node = Monitor::new(monitor.scene().clone());
    let mut node_events: Vec<Event> = node_stream
        .inputs()
        .filter_map(|input| match input {
            coalshock_replay::Input::Sample(s) => node.feed(s),
            coalshock_replay::Input::Gap(lost) => node.gap(lost),
        })
        .collect();
    node_events.extend(node.finish());
    let same = node_events == events && node.counters() == monitor.counters();
    if !same {
        // Host only (not among the compared lines): where the two replays part.
        let first = node_events
            .iter()
            .zip(events.iter())
            .position(|(a, b)| a != b)
            .unwrap_or(node_events.len().min(events.len()));
        println!(
            "{prefix}feed_check same=0 feed_events={} slice_events={} first_difference={first}",
            node_events.len(),
            events.len()
        );
        fail("replay: one feed per sample and feed_slice blocks give different events".into());
    }
    let classes: &[ParticleClass] = monitor.scene().classes();
    for (n, e) in events.iter().enumerate() {
        match e {
            Event::Pulse(r) => {
                let l = PulseLine::new(r, classes);
                println!(
                    "{prefix}pulse {} at={} {} {} p_ppm={} F_mN={} t_ns={}",
                    n, l.at, l.kind, l.who, l.posterior_ppm, l.force_mn, l.duration_ns
                );
            }
            Event::Stuck { at_sample } => println!("{prefix}stuck at={at_sample}"),
            Event::Flow(f) => println!(
                "{prefix}flow pulses={} share_ppm={} alarm={}",
                f.pulses,
                (f.share * 1e6) as u32,
                f.alarm
            ),
        }
    }
    let c = monitor.counters();
    for (class, count) in classes.iter().zip(c.classified.iter()) {
        println!("{prefix}classified {} {}", class.name.as_str(), count);
    }
    for reason in RejectReason::ALL {
        println!(
            "{prefix}rejected {} {}",
            reason.name(),
            c.rejected_for(reason)
        );
    }
    let l = CounterLine::new(c);
    println!(
        "{prefix}counters samples={} pulses={} ambiguous={} out={} rejected={} stuck={} gaps={} lost={} balanced={}",
        l.samples, l.pulses, l.ambiguous, l.out, l.rejected, l.stuck, l.gaps, l.lost, l.balanced
    );

    // Against the truth (not compared with the node): reports paired with impacts by peak time.
    let reports: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Event::Pulse(r) => Some(*r),
            Event::Stuck { .. } | Event::Flow(_) => None,
        })
        .collect();
    let m = match_truth(&reports, &stream.truth, 3);
    // Clean impacts by verdict: right class, wrong class, ambiguous, out, rejected.
    let mut clean = [0u32; 5];
    for p in &m.pairs {
        let (Some(r), Some(t)) = (reports.get(p.report), stream.truth.get(p.truth)) else {
            continue;
        };
        if t.fault != ImpactFault::None {
            continue;
        }
        let slot = match r.verdict {
            Verdict::Class { class, .. } if class as usize == t.class => 0,
            Verdict::Class { .. } => 1,
            Verdict::Ambiguous { .. } => 2,
            Verdict::OutOfEnvelope { .. } => 3,
            Verdict::Rejected(_) => 4,
        };
        clean[slot] += 1;
    }
    println!(
        "{prefix}truth impacts={} faulty={} reports={} paired={} clean: right={} wrong={} ambiguous={} out={} rejected={}",
        stream.truth.len(),
        stream
            .truth
            .iter()
            .filter(|t| t.fault != ImpactFault::None)
            .count(),
        reports.len(),
        m.pairs.len(),
        clean[0],
        clean[1],
        clean[2],
        clean[3],
        clean[4]
    );
}
