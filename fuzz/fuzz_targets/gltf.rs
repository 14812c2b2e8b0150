//! libFuzzer target: `reshift_fuzz::gltf` (see fuzz/README.md).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| reshift_fuzz::gltf(data));
