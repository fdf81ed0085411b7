//! springlab-render: the software renderer ([`render`]), re-exported by `springlab` as
//! `springlab::render`. The core modules are re-exported here under their own names, so the
//! renderer's `crate::scene`, `crate::physics`, … paths read as in one crate.

#![allow(clippy::needless_range_loop)]
#![deny(unsafe_code)]

pub mod render;

use springlab_core::{output, physics, scene, simulation};
