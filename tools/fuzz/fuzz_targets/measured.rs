#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| pbrt_sppm::cli::fuzzing::measured(data));
