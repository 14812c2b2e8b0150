// Every method family the CLI knows, one line each, in the order `reshift methods` lists them:
// the module (a file `src/<name>.rs` or a folder `src/<name>/`, declared in src/lib.rs) whose
// `ENTRY` it registers, `with contract` where the folder has a `contract.rs` for its GLSL.
// src/lib.rs reads this list (`REGISTRY`), and so does build.rs (the contracts to render).
registry! {
    pt with contract,
    restir,
    random_walk,
    pt_one_hit,
    single_scatter with contract,
    image_space with contract,
    adaptive with contract,
}
