//! Raw bindings to `shim/snake_shim.h`, a small `extern "C"` layer over Bullet's btMultiBody API that
//! builds and steps worlds exactly as pybullet 3.2.7 does (see the header for every call's contract).
//!
//! This crate is `unsafe` by nature; use the safe `snake-core` crate instead.
#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

include!(concat!(env!("OUT_DIR"), "/bindings.rs"));
