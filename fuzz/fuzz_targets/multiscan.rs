#![no_main]
//! `cargo fuzz run multiscan`: see `partscene_fuzz::multiscan`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::multiscan(data);
});
