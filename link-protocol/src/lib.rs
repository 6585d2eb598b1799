#![no_std]
//! Frames between the host and the firmware (filled in by the firmware work).
