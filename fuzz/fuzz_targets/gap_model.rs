#![no_main]
//! `cargo fuzz run gap_model`: see `partscene_fuzz::gap_model`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::gap_model(data);
});
