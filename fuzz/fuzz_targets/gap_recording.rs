#![no_main]
//! `cargo fuzz run gap_recording`: see `partscene_fuzz::gap_recording`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::gap_recording(data);
});
