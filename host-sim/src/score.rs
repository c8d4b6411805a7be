//! Layer 5, score: the kernel measured on simulated impacts — replay, the Bayes and Cramér-Rao
//! limits, the reference detector, reliability and the studies built on them. Imports every
//! layer below (physics, scene, sim, bridge).

pub mod bayes;
pub mod caving;
pub mod counts;
pub mod crb;
pub mod cusum;
pub mod evaluate;
pub mod mismatch;
pub mod noise_check;
pub mod peak_snr;
pub mod reference;
pub mod reliability;
pub mod replay;
pub mod saturation;
pub mod study_error;
pub mod yield_bayes;
