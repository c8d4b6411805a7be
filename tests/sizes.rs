//! The RAM the optional features and the optional flow monitor add, as `Cargo.toml`, the
//! types' docs and `docs/caving.md` state it: each figure is `size_of` of the type added (host
//! target; the same layout of `f32` fields on a Cortex-M).

/// `pulse_shape`: one `PulseShape` per `Settings`, 544 B (65 points of `g` and `dg/du`, 520 B,
/// and its area, peak, reach and errors).
#[cfg(feature = "pulse_shape")]
#[test]
fn a_pulse_shape_takes_544_bytes() {
    use coalshock::pulse_shape::{PulseShape, SHAPE_POINTS};
    assert_eq!(2 * SHAPE_POINTS * core::mem::size_of::<f32>(), 520);
    assert_eq!(core::mem::size_of::<PulseShape>(), 544);
}

/// `pulse_shape` with `settle`: one `Option<ClipColumns>` per `Settler`, 100 B (three columns
/// of the sections' states, `3 x 8 x 4` B, and the option's tag).
#[cfg(all(feature = "pulse_shape", feature = "settle"))]
#[test]
fn a_settler_holds_100_bytes_of_clip_columns() {
    use coalshock::settle_clip::ClipColumns;
    assert_eq!(
        core::mem::size_of::<ClipColumns>(),
        3 * 8 * core::mem::size_of::<f32>()
    );
    assert_eq!(core::mem::size_of::<Option<ClipColumns>>(), 100);
}

/// `sampled_phase`: one `SampledPhase` per `Settings`, 1 360 B.
#[cfg(feature = "sampled_phase")]
#[test]
fn a_sampled_phase_table_takes_1360_bytes() {
    assert_eq!(core::mem::size_of::<coalshock::SampledPhase>(), 1360);
}

/// The flow monitor (`Monitor::with_flow`), with or without any feature: a `FlowMonitor` holds
/// 204 B, 128 B of them the log priors of up to `MAX_CLASSES` (32) classes; its config, 20 B.
#[test]
fn a_flow_monitor_takes_204_bytes() {
    use coalshock::math::{Libm, Micromath};
    use coalshock::scene::MAX_CLASSES;
    use coalshock::{FlowConfig, FlowMonitor};
    assert_eq!(MAX_CLASSES * core::mem::size_of::<f32>(), 128);
    assert_eq!(core::mem::size_of::<FlowConfig>(), 20);
    assert_eq!(core::mem::size_of::<FlowMonitor<Libm>>(), 204);
    assert_eq!(core::mem::size_of::<FlowMonitor<Micromath>>(), 204);
}

/// `noise_colour`: a `NoiseColour` of 15 `f32` (the sums' variances at 9 widths, the slope
/// past them and 5 correlations), 60 B in each copy of an `EqualiserDesign` (the scene's, the
/// chain's own and the monitor's equaliser's) and 64 B as the detector's `Option`.
#[cfg(feature = "noise_colour")]
#[test]
fn a_noise_colour_takes_60_bytes() {
    use coalshock::noise_colour::{LAGS, NoiseColour, WIDTHS};
    assert_eq!(
        (WIDTHS.len() + 1 + LAGS + 1) * core::mem::size_of::<f32>(),
        60
    );
    assert_eq!(core::mem::size_of::<NoiseColour>(), 60);
    assert_eq!(core::mem::size_of::<Option<NoiseColour>>(), 64);
}
