#![no_main]
//! `cargo fuzz run gap_mcap`: see `partscene_fuzz::gap_mcap`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::gap_mcap(data);
});
