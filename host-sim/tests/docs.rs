//! The docs' command blocks (```console in README.md and docs/host-sim.md) run as written,
//! their outputs compared (trycmd): a change of a command's output, or a doc edited without
//! running it, fails here. `TRYCMD=overwrite cargo test -p host-sim --test docs` writes the
//! outputs back (read the diff before committing it). Run from host-sim/ (its `out/` takes
//! what the commands write).

#[test]
fn the_command_blocks_of_the_docs_are_what_the_commands_print() {
    trycmd::TestCases::new()
        .register_bin(
            "host-sim",
            std::path::Path::new(env!("CARGO_BIN_EXE_host-sim")),
        )
        .case("../README.md")
        .case("../docs/host-sim.md");
}
