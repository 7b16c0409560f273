#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pkm_fuzz::batch_table(data));
