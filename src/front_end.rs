//! Accelerometer front ends (in progress).
