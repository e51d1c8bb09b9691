#![no_main]
//! `cargo fuzz run scan_ply`: see `partscene_fuzz::scan_ply`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::scan_ply(data);
});
