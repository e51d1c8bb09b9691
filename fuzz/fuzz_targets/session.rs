#![no_main]
//! `cargo fuzz run session`: see `partscene_fuzz::session`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::session(data);
});
