fn main() {
    let (_, scan) = partscene::synth::demo(0);
    let cfg = partscene::pipeline::PipelineConfig::default();
    let part = scan.part(203).unwrap();
    let fit = partscene::fit::fit_part(&part.points, &cfg.fit, None).unwrap();
    println!("{:?} err {}", fit.primitive, fit.fit_error);
    let body = scan.part(201).unwrap();
    let bf = partscene::fit::fit_part(&body.points, &cfg.fit, None).unwrap();
    println!("{:?}", bf.primitive);
    let rot = partscene::refine::aligning_rotation(&bf.primitive, &fit.primitive, 0.707);
    println!("{rot:?}");
}
