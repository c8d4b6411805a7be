//! Count bounds of the command line: the largest number of impacts, draws or rounds a flag
//! may ask for, and the parser that refuses a count outside `1..=max` by the flag's name and
//! the bound (instead of an allocation abort or an overflow panic).
//!
//! Each bound keeps the memory a run holds below a few GB and its time below a day on one
//! core; a larger study is several runs with different seeds.

/// `evaluate --n`: impacts per class. Each impact's outcome (about 150 bytes) is held until
/// the end: 10^7 per class is 1.5 GB per class.
pub const MAX_IMPACTS_PER_CLASS: usize = 10_000_000;

/// `evaluate --bayes-draws`: Monte Carlo draws per class of the Bayes limit (nothing is
/// held; at 10^8 the standard error is below 5e-5, and the run takes hours).
pub const MAX_BAYES_DRAWS_PER_CLASS: usize = 100_000_000;

/// `stream --n`: impacts of one stream. The time line is further bounded by
/// [`crate::sim::stream::MAX_STREAM_SAMPLES`].
pub const MAX_STREAM_IMPACTS: usize = 10_000_000;

/// `caving --rounds`: each round simulates `--pre-impacts + --post-impacts` impacts.
pub const MAX_CAVING_ROUNDS: usize = 100_000;

/// `caving --pre-impacts`, `--post-impacts`, `--ramp-impacts`: impacts of one round (held
/// in memory while the round runs).
pub const MAX_ROUND_IMPACTS: usize = 1_000_000;

/// `caving --naive-n`: pulses the naive rule looks back on (its setting is searched over
/// `1..=n`, each step replaying `--false-alarm-impacts` impacts).
pub const MAX_NAIVE_N: usize = 10_000;

/// `caving --false-alarm-impacts`: background impacts behind each false-alarm rate.
pub const MAX_FALSE_ALARM_IMPACTS: usize = 1_000_000_000;

/// A count from the command line: a whole number in `1..=max`, else a message stating the
/// range and what the count is of (`unit`, e.g. "impacts per class"). Clap prefixes it with
/// the flag: `invalid value '0' for '--n <N>': ...`.
pub fn parse_count(text: &str, max: usize, unit: &str) -> Result<usize, String> {
    let range = format!("a whole number of {unit} from 1 to {max}");
    match text.trim().parse::<u128>() {
        Ok(v) if v >= 1 && v <= max as u128 => Ok(v as usize),
        Ok(v) => Err(format!("{v} is outside the bound: give {range}")),
        Err(_) => Err(format!("{text:?} is not {range}")),
    }
}

/// `evaluate --n` (see [`MAX_IMPACTS_PER_CLASS`]).
pub fn impacts_per_class(text: &str) -> Result<usize, String> {
    parse_count(text, MAX_IMPACTS_PER_CLASS, "impacts per class")
}

/// `evaluate --bayes-draws` (see [`MAX_BAYES_DRAWS_PER_CLASS`]).
pub fn bayes_draws_per_class(text: &str) -> Result<usize, String> {
    parse_count(text, MAX_BAYES_DRAWS_PER_CLASS, "draws per class")
}

/// `stream --n` (see [`MAX_STREAM_IMPACTS`]).
pub fn stream_impacts(text: &str) -> Result<usize, String> {
    parse_count(text, MAX_STREAM_IMPACTS, "impacts")
}

/// `caving --rounds` (see [`MAX_CAVING_ROUNDS`]).
pub fn caving_rounds(text: &str) -> Result<usize, String> {
    parse_count(text, MAX_CAVING_ROUNDS, "rounds")
}

/// `caving --pre-impacts`, `--post-impacts`, `--ramp-impacts` (see [`MAX_ROUND_IMPACTS`]).
pub fn round_impacts(text: &str) -> Result<usize, String> {
    parse_count(text, MAX_ROUND_IMPACTS, "impacts per round")
}

/// `caving --naive-n` (see [`MAX_NAIVE_N`]).
pub fn naive_pulses(text: &str) -> Result<usize, String> {
    parse_count(text, MAX_NAIVE_N, "pulses")
}

/// `caving --false-alarm-impacts` (see [`MAX_FALSE_ALARM_IMPACTS`]).
pub fn false_alarm_impacts(text: &str) -> Result<usize, String> {
    parse_count(text, MAX_FALSE_ALARM_IMPACTS, "impacts")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_outside_the_bound_are_refused_with_it() {
        assert_eq!(parse_count("7", 10, "impacts"), Ok(7));
        assert_eq!(parse_count("10", 10, "impacts"), Ok(10));
        for bad in ["0", "11", "18446744073709551615", "99999999999999999999999"] {
            let e = parse_count(bad, 10, "impacts").expect_err(bad);
            assert!(e.contains("from 1 to 10") && e.contains("impacts"), "{e}");
        }
        let e = parse_count("1e6", 10, "impacts").expect_err("not whole");
        assert!(e.contains("not a whole number"), "{e}");
    }
}
