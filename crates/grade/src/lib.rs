//! springlab-grade: homework grading ([`grade`]), re-exported by `springlab` as
//! `springlab::grade`. The core modules are re-exported here under their own names, so the
//! grader's `crate::physics`, `crate::scene`, … paths read as in one crate.

#![allow(clippy::needless_range_loop)]
// Unchecked code (the lint below) only in the process sandbox (fork/exec and limits).
#![deny(unsafe_code)]

pub mod grade;

use springlab_core::{physics, random, scene, simulation};
