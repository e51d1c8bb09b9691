#![no_main]
//! `cargo fuzz run scan_npz`: see `partscene_fuzz::scan_npz`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::scan_npz(data);
});
