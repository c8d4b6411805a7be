//! The one error of the scoring studies (`host-sim evaluate` and `host-sim caving`): what a
//! scene, its conversion to the kernel, a stream, the reference limit or an option can be
//! wrong with.

use crate::bridge::convert::ConvertError;
use crate::scene::SceneError;
use crate::score::reference::ReferenceError;
use crate::sim::stream::StreamError;

/// Why a study (an evaluation, caving rounds) could not run.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The scene file is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The kernel refused the scene.
    #[error(transparent)]
    Convert(#[from] ConvertError),
    /// A stream could not be simulated.
    #[error(transparent)]
    Stream(#[from] StreamError),
    /// The reference limit could not be computed.
    #[error(transparent)]
    Reference(#[from] ReferenceError),
    /// An option is out of range.
    #[error("{study} option {field} {problem}")]
    Option {
        /// The study the option belongs to (`evaluation`, `caving`).
        study: &'static str,
        /// The option.
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
}

impl StudyError {
    /// A [`StudyError::Option`] of `study` on `field`.
    pub fn option(study: &'static str, field: &'static str, problem: impl Into<String>) -> Self {
        StudyError::Option {
            study,
            field,
            problem: problem.into(),
        }
    }
}
