//! Bad input: every parameter a scene is built from, made bad one at a time, gives the typed
//! error that names it, at scene build (never a panic, never a scene).
//!
//! The base is the paper's two-class scene (coal and sandstone on carbon steel) with an
//! explicit sensor chain and settings; each case changes exactly one field.

use coalshock::scene::MAX_CLASSES;
use coalshock::{Error, Material, ParticleClass, Range, Scene, SensorChain, Settings, Speed};

const NAN: f32 = f32::NAN;
const INF: f32 = f32::INFINITY;

/// NaN, infinities, zeros, negative values, and positive values outside `1e-30..1e30`
/// (subnormal included): what every strictly positive float field must refuse, with the error
/// each must give for a field named `name`.
fn bad_positive(name: &'static str) -> Vec<(f32, Error)> {
    vec![
        (1e-45, Error::Unrepresentable(name)),
        (1e-31, Error::Unrepresentable(name)),
        (1.01e30, Error::Unrepresentable(name)),
        (f32::MAX, Error::Unrepresentable(name)),
        (NAN, Error::NonFinite(name)),
        (INF, Error::NonFinite(name)),
        (-INF, Error::NonFinite(name)),
        (0.0, Error::NonPositive(name)),
        (-0.0, Error::NonPositive(name)),
        (-1.0, Error::NonPositive(name)),
        (-f32::MIN_POSITIVE, Error::NonPositive(name)),
    ]
}

/// The valid base scene's parts.
#[derive(Clone)]
struct Parts {
    plate: Material,
    classes: Vec<ParticleClass>,
    sensor: SensorChain,
    settings: Settings,
}

fn base() -> Parts {
    let r = Range::new(0.015, 0.04);
    let u = Speed::Uniform(Range::new(2.5, 3.5));
    Parts {
        plate: Material::CARBON_STEEL,
        classes: vec![
            ParticleClass::new("coal", Material::COAL, r, u),
            ParticleClass::new("gangue", Material::SANDSTONE, r, u),
        ],
        sensor: SensorChain {
            sample_rate_hz: 100_000.0,
            force_per_count_n: 50.0 / 30.0,
            noise_rms_counts: 4.0,
            adc_min: -32768,
            adc_max: 32767,
            dynamics: coalshock::ChainDynamics::RIGID,
        },
        settings: Settings::default(),
    }
}

fn build(p: &Parts) -> Result<Scene, Error> {
    Scene::new(p.plate, &p.classes, p.sensor, p.settings)
}

/// Builds `base()` changed by `change` and checks the error.
fn expect(what: &str, want: Error, change: impl FnOnce(&mut Parts)) {
    let mut p = base();
    change(&mut p);
    let got = build(&p).map(|s| s.separability());
    assert_eq!(got, Err(want), "{what}");
}

/// Builds `base()` changed by `change` and checks it is accepted.
fn accepted(what: &str, change: impl FnOnce(&mut Parts)) {
    let mut p = base();
    change(&mut p);
    if let Err(e) = build(&p) {
        panic!("{what}: refused with {e:?}");
    }
}

#[test]
fn the_base_scene_builds() {
    accepted("base", |_| {});
}

/// Every Material field of the plate, and of each class's particle.
#[test]
fn material_fields() {
    type Field = fn(&mut Material) -> &mut f32;
    let fields: [(&'static str, Field); 2] = [
        ("density_kg_m3", |m| &mut m.density_kg_m3),
        ("modulus_pa", |m| &mut m.modulus_pa),
    ];
    // Which material: the plate, or the particle of class 0 or 1.
    type Which = fn(&mut Parts) -> &mut Material;
    let whose: [(&str, Which); 3] = [
        ("plate", |p| &mut p.plate),
        ("class 0", |p| &mut p.classes[0].material),
        ("class 1", |p| &mut p.classes[1].material),
    ];
    for (who, which) in whose {
        for (name, field) in fields {
            for (v, err) in bad_positive(name) {
                expect(&format!("{who} {name} = {v}"), err, |p| {
                    *field(which(p)) = v
                });
            }
        }
        for v in [NAN, INF, -INF] {
            expect(
                &format!("{who} poisson = {v}"),
                Error::NonFinite("poisson"),
                |p| which(p).poisson = v,
            );
        }
        for v in [-0.1, -1.0, -f32::MIN_POSITIVE, 0.5, 0.7, 1.0, f32::MAX] {
            expect(
                &format!("{who} poisson = {v}"),
                Error::PoissonOutOfRange,
                |p| which(p).poisson = v,
            );
        }
        // Zero and just below one half are valid Poisson's ratios.
        for v in [0.0, -0.0, 0.499_999_97] {
            accepted(&format!("{who} poisson = {v}"), |p| which(p).poisson = v);
        }
    }
}

/// Both ends of a class's radius range, uniform speed range and drop-height range.
#[test]
fn range_fields() {
    // (field name, the class's (radius, speed) with that range in place)
    type Make = fn(Range) -> (Range, Speed);
    let ranges: [(&'static str, Make); 3] = [
        ("radius_m", |r| (r, Speed::Uniform(Range::new(2.5, 3.5)))),
        ("speed_m_s", |r| {
            (Range::new(0.015, 0.04), Speed::Uniform(r))
        }),
        ("drop_height_m", |r| {
            (Range::new(0.015, 0.04), Speed::DropHeight(r))
        }),
    ];
    // A valid range for each: radius in m, speed in m/s, height in m (0.32 to 0.62 m gives
    // 2.5 to 3.5 m/s).
    let valid = [
        Range::new(0.015, 0.04),
        Range::new(2.5, 3.5),
        Range::new(0.32, 0.62),
    ];
    for ((name, make), ok) in ranges.into_iter().zip(valid) {
        for class in 0..2 {
            let set = |p: &mut Parts, r: Range| {
                let (radius, speed) = make(r);
                if name == "radius_m" {
                    p.classes[class].radius_m = radius;
                } else {
                    p.classes[class].speed = speed;
                }
            };
            accepted(&format!("class {class} {name} {ok:?}"), |p| set(p, ok));
            for (v, err) in bad_positive(name) {
                expect(&format!("class {class} {name}.min = {v}"), err, |p| {
                    set(p, Range::new(v, ok.max))
                });
                expect(&format!("class {class} {name}.max = {v}"), err, |p| {
                    set(p, Range::new(ok.min, v))
                });
            }
            expect(
                &format!("class {class} {name} inverted"),
                Error::InvertedRange(name),
                |p| set(p, Range::new(ok.max, ok.min)),
            );
            expect(
                &format!("class {class} {name} empty"),
                Error::InvertedRange(name),
                |p| set(p, Range::new(ok.min, ok.min)),
            );
            // Narrower than 1e-4 in log space (one ulp, or 5e-5 relative): f32 cannot
            // resolve it. A drop-height range is checked as the speed range it gives.
            let narrow = if name == "radius_m" {
                Error::OutOfRange("radius_m (range narrower than 1e-4 relative)")
            } else {
                Error::OutOfRange("speed_m_s (range narrower than 1e-4 relative)")
            };
            let one_ulp = f32::from_bits(ok.min.to_bits() + 1);
            for hi in [one_ulp, ok.min * (1.0 + 5e-5)] {
                let what = format!("class {class} {name} [{}, {hi}]", ok.min);
                if name == "drop_height_m" && cfg!(feature = "micromath") {
                    // micromath's sqrt is not monotonic at the ulp level: the two speeds of a
                    // one-ulp height range can come out in the wrong order.
                    let mut p = base();
                    set(&mut p, Range::new(ok.min, hi));
                    let got = build(&p).map(|s| s.separability());
                    assert!(
                        got == Err(narrow) || got == Err(Error::InvertedRange("speed_m_s")),
                        "{what}: {got:?}"
                    );
                } else {
                    expect(&what, narrow, |p| set(p, Range::new(ok.min, hi)));
                }
            }
            accepted(&format!("class {class} {name} 1e-3 wide"), |p| {
                set(p, Range::new(ok.min, ok.min * 1.001))
            });
        }
    }
}

#[test]
fn prior_field() {
    for class in 0..2 {
        for (v, err) in bad_positive("prior") {
            expect(&format!("class {class} prior = {v}"), err, |p| {
                p.classes[class].prior = v
            });
        }
        accepted(&format!("class {class} prior = 3"), |p| {
            p.classes[class].prior = 3.0
        });
    }
}

#[test]
fn sensor_fields() {
    for (v, err) in bad_positive("sample_rate_hz") {
        expect(&format!("sample_rate_hz = {v}"), err, |p| {
            p.sensor.sample_rate_hz = v
        });
    }
    for (v, err) in bad_positive("force_per_count_n") {
        expect(&format!("force_per_count_n = {v}"), err, |p| {
            p.sensor.force_per_count_n = v
        });
    }
    for v in [NAN, INF, -INF] {
        expect(
            &format!("noise_rms_counts = {v}"),
            Error::NonFinite("noise_rms_counts"),
            |p| p.sensor.noise_rms_counts = v,
        );
    }
    for v in [-1.0, -f32::MIN_POSITIVE] {
        expect(
            &format!("noise_rms_counts = {v}"),
            Error::NonPositive("noise_rms_counts"),
            |p| p.sensor.noise_rms_counts = v,
        );
    }
    // A noiseless (simulated) sensor is allowed.
    accepted("noise_rms_counts = 0", |p| p.sensor.noise_rms_counts = 0.0);
    for (lo, hi) in [
        (0, 0),
        (1, 0),
        (32767, -32768),
        (i32::MAX, i32::MIN),
        (5, 5),
    ] {
        expect(
            &format!("adc {lo}..{hi}"),
            Error::InvertedRange("adc_min..adc_max"),
            |p| {
                p.sensor.adc_min = lo;
                p.sensor.adc_max = hi;
            },
        );
    }
    accepted("adc full i32", |p| {
        p.sensor.adc_min = i32::MIN;
        p.sensor.adc_max = i32::MAX;
    });
    // from_plate with zero sensitivity: the force per count is infinite.
    expect(
        "from_plate, 0 counts per m/s^2",
        Error::NonFinite("force_per_count_n"),
        |p| p.sensor = SensorChain::from_plate(100_000.0, 50.0, 0.0, 4.0, 16),
    );
    expect(
        "from_plate, 0 kg plate",
        Error::NonPositive("force_per_count_n"),
        |p| p.sensor = SensorChain::from_plate(100_000.0, 0.0, 30.0, 4.0, 16),
    );
}

#[test]
fn sample_rate_too_low_for_the_shortest_pulse() {
    let scene = build(&base()).unwrap();
    let (shortest, _) = scene.duration_bounds_s();
    // 1 kS/s: the shortest pulse (~0.12 ms) is a tenth of a sample.
    let low = Error::OutOfRange("sample_rate_hz (shortest pulse < 2.5 samples)");
    expect("1 kS/s", low, |p| p.sensor.sample_rate_hz = 1000.0);
    // Just below and just above 2.5 samples per shortest pulse.
    expect("2.49 samples per shortest pulse", low, |p| {
        p.sensor.sample_rate_hz = 2.49 / shortest
    });
    accepted("2.51 samples per shortest pulse", |p| {
        p.sensor.sample_rate_hz = 2.51 / shortest
    });
    // The smallest rate the kernel carries (1e-30 S/s).
    expect("1e-30 S/s", low, |p| p.sensor.sample_rate_hz = 1e-30);
}

#[test]
fn settings_fields() {
    type Field = fn(&mut Settings) -> &mut f32;
    let positive: [(&'static str, Field); 4] = [
        ("trigger_sigmas", |s| &mut s.trigger_sigmas),
        ("release_sigmas", |s| &mut s.release_sigmas),
        ("baseline_tau_s", |s| &mut s.baseline_tau_s),
        ("out_sigmas", |s| &mut s.out_sigmas),
    ];
    for (name, field) in positive {
        for (v, err) in bad_positive(name) {
            expect(&format!("{name} = {v}"), err, |p| {
                *field(&mut p.settings) = v
            });
        }
    }
    expect(
        "release above trigger",
        Error::InvertedRange("release_sigmas..trigger_sigmas"),
        |p| p.settings.release_sigmas = p.settings.trigger_sigmas * 1.5,
    );
    accepted("release equal to trigger", |p| {
        p.settings.release_sigmas = p.settings.trigger_sigmas
    });
    for v in [NAN, INF, -INF, -0.01, -1.0] {
        expect(
            &format!("model_sigma = {v}"),
            Error::OutOfRange("model_sigma"),
            |p| p.settings.model_sigma = v,
        );
    }
    accepted("model_sigma = 0", |p| p.settings.model_sigma = 0.0);
    for v in [NAN, INF, -INF, 0.0, -0.01, 0.5, 0.6, 1.0, 1.5] {
        expect(
            &format!("confident_error_rate = {v}"),
            Error::OutOfRange("confident_error_rate"),
            |p| p.settings.confident_error_rate = v,
        );
    }
    accepted("confident_error_rate = 0.49", |p| {
        p.settings.confident_error_rate = 0.49
    });
    accepted("confident_error_rate = 1e-6", |p| {
        p.settings.confident_error_rate = 1e-6
    });
    expect(
        "hold_samples = 0",
        Error::NonPositive("hold_samples"),
        |p| p.settings.hold_samples = 0,
    );
    accepted("hold_samples = max", |p| p.settings.hold_samples = u16::MAX);
    accepted("stuck_samples = 0 (off)", |p| p.settings.stuck_samples = 0);
    accepted("stuck_samples = max", |p| {
        p.settings.stuck_samples = u16::MAX
    });
    for g in [0u16, 1, 257, u16::MAX] {
        expect(
            &format!("separability_grid = {g}"),
            Error::OutOfRange("separability_grid"),
            |p| p.settings.separability_grid = g,
        );
    }
    for g in [2u16, 256] {
        accepted(&format!("separability_grid = {g}"), |p| {
            p.settings.separability_grid = g
        });
    }
    for v in [NAN, INF, -INF, 0.0, -0.02] {
        expect(
            &format!("shape_tolerance = {v}"),
            Error::OutOfRange("shape_tolerance"),
            |p| p.settings.shape_tolerance = v,
        );
    }
    for v in [NAN, INF, 0.0, -1.0, 9e-4, 1.1e3] {
        expect(
            &format!("force_ratio = {v}"),
            Error::OutOfRange("contact.force_ratio"),
            |p| p.settings.contact.force_ratio = v,
        );
        expect(
            &format!("duration_ratio = {v}"),
            Error::OutOfRange("contact.duration_ratio"),
            |p| p.settings.contact.duration_ratio = v,
        );
        expect(
            &format!("shape_ratio = {v}"),
            Error::OutOfRange("contact.shape_ratio"),
            |p| p.settings.contact.shape_ratio = v,
        );
    }
    for v in [NAN, INF, 0.0, -0.3] {
        expect(
            &format!("spike_fraction = {v}"),
            Error::OutOfRange("spike_fraction"),
            |p| p.settings.spike_fraction = v,
        );
    }
    for v in [NAN, INF, 0.0, -0.05] {
        expect(
            &format!("skew_tolerance = {v}"),
            Error::OutOfRange("skew_tolerance"),
            |p| p.settings.skew_tolerance = v,
        );
    }
    for v in [NAN, INF, -INF, 10.5, -11.0] {
        expect(
            &format!("skewness = {v}"),
            Error::OutOfRange("contact.skewness"),
            |p| p.settings.contact.skewness = v,
        );
    }
    accepted("contact ratios 0.5, 0.7, 0.9", |p| {
        p.settings.contact.force_ratio = 0.5;
        p.settings.contact.duration_ratio = 0.7;
        p.settings.contact.shape_ratio = 0.9;
    });
}

#[test]
fn class_list_empty_one_or_too_long() {
    expect("no class", Error::TooFewClasses, |p| p.classes.clear());
    expect("one class", Error::TooFewClasses, |p| p.classes.truncate(1));
    let p = base();
    let mut three = p.classes.clone();
    three.push(ParticleClass::new(
        "mudstone",
        Material::SANDY_MUDSTONE,
        Range::new(0.015, 0.04),
        Speed::Uniform(Range::new(2.5, 3.5)),
    ));
    assert_eq!(
        Scene::<2>::new(p.plate, &three, p.sensor, p.settings).map(|s| s.separability()),
        Err(Error::TooManyClasses)
    );
    assert!(Scene::<3>::new(p.plate, &three, p.sensor, p.settings).is_ok());
    // A capacity above MAX_CLASSES still stops at MAX_CLASSES.
    let many: Vec<ParticleClass> = (0..=MAX_CLASSES)
        .map(|i| p.classes[i % 2].clone())
        .collect();
    assert_eq!(
        Scene::<40>::new(p.plate, &many, p.sensor, p.settings).map(|s| s.separability()),
        Err(Error::TooManyClasses)
    );
}

#[test]
fn checks_on_the_parts() {
    // Range::checked and Material::validate on their own give the same errors.
    assert_eq!(
        Range::new(1.0, 1.0).checked("r"),
        Err(Error::InvertedRange("r"))
    );
    assert_eq!(
        Range::new(2.0, 1.0).checked("r"),
        Err(Error::InvertedRange("r"))
    );
    assert_eq!(
        Range::new(NAN, 1.0).checked("r"),
        Err(Error::NonFinite("r"))
    );
    assert_eq!(
        Range::new(1.0, INF).checked("r"),
        Err(Error::NonFinite("r"))
    );
    assert_eq!(
        Range::new(-1.0, 1.0).checked("r"),
        Err(Error::NonPositive("r"))
    );
    assert_eq!(
        Range::new(0.0, 1.0).checked("r"),
        Err(Error::NonPositive("r"))
    );
    assert!(Range::new(1.0, 2.0).checked("r").is_ok());
    assert_eq!(
        Material::new(NAN, 1e9, 0.3).validate(),
        Err(Error::NonFinite("density_kg_m3"))
    );
    assert_eq!(
        Material::new(1e3, -1e9, 0.3).validate(),
        Err(Error::NonPositive("modulus_pa"))
    );
    assert_eq!(
        Material::new(1e3, 1e9, 0.5).validate(),
        Err(Error::PoissonOutOfRange)
    );
    assert!(Material::COAL.validate().is_ok());
}
