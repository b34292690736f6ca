//! `NEO_HDL_DIR` read when the tests run (`neo_tb::hdl_dir`): a linked model whose files in the
//! directory are the ones it was built from runs as linked; when one differs, the wrapper runs a
//! model of the directory's Verilog (and behaves as that Verilog does); a missing file is an
//! error naming it. Every file compared is listed in `DIR/neo-tb-read.txt`.
//!
//! One test in its own binary: it sets `NEO_HDL_DIR` in the process environment.

#[cfg(not(neo_has_verilator))]
#[test]
fn hdl_dir_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models("hdl_dir_skipped_without_verilator: NEO_HDL_DIR not checked"));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_tb::hdl_dir::READ_LIST;
    use neo_tb::models::NeoBsu;
    use std::path::Path;

    /// `in_ready_o` with a sorted vector waiting under backpressure: low in the generated BSU
    /// (the whole network stalls), high in the mutant whose `in_ready_o` is stuck at 1.
    fn ready_while_blocked(dut: &mut NeoBsu) -> bool {
        dut.set_in_valid_i(false);
        dut.set_out_ready_i(false);
        dut.reset();
        dut.set_in_valid_i(true);
        for _ in 0..64 {
            dut.tick();
        }
        assert!(dut.out_valid_o(), "a vector reaches the output within 64 cycles");
        dut.eval();
        dut.in_ready_o()
    }

    /// Writes the BSU's files (as `neo gen` does) into `dir`, `edit` applied to `neo_bsu.v`.
    fn write_bsu(dir: &Path, edit: impl Fn(&str) -> String) {
        std::fs::create_dir_all(dir).unwrap();
        for f in neo_gen::files_for(&neo_tb::config(), "neo_bsu") {
            let name = f.file_name();
            let text = if f.name == "neo_bsu" { edit(&f.text) } else { f.text };
            std::fs::write(dir.join(name), text).unwrap();
        }
    }

    fn read_list(dir: &Path) -> String {
        std::fs::read_to_string(dir.join(READ_LIST)).unwrap_or_default()
    }

    #[test]
    fn a_changed_file_in_neo_hdl_dir_runs_instead_of_the_linked_model() {
        if !neo_tb::require_models("a_changed_file_in_neo_hdl_dir_runs_instead_of_the_linked_model") {
            return;
        }
        assert_eq!(NeoBsu::HDL_FILES, ["neo_cmp_swap.v", "neo_bsu.v"]);
        let tmp = tempfile::tempdir().unwrap();
        let linked = ready_while_blocked(&mut NeoBsu::new());
        assert!(!linked, "the generated BSU stalls its input under backpressure");

        // The same Verilog: the linked model, both files compared.
        let same = tmp.path().join("same");
        write_bsu(&same, str::to_string);
        std::env::set_var("NEO_HDL_DIR", &same);
        let mut dut = NeoBsu::new();
        assert!(!dut.is_substituted());
        assert!(!ready_while_blocked(&mut dut));
        assert_eq!(read_list(&same), "neo_cmp_swap.v\nneo_bsu.v\n");

        // A mutant: a model of it, which behaves as it.
        let mutant = tmp.path().join("mutant");
        write_bsu(&mutant, |t| {
            assert!(t.contains("\n  assign in_ready_o = en;\n"), "the BSU's in_ready_o assignment moved");
            t.replace("\n  assign in_ready_o = en;\n", "\n  assign in_ready_o = 1'b1;\n")
        });
        std::env::set_var("NEO_HDL_DIR", &mutant);
        let mut dut = NeoBsu::new();
        assert!(dut.is_substituted());
        assert!(ready_while_blocked(&mut dut), "the mutant's in_ready_o is stuck high");
        assert_eq!(dut.cycle(), 64, "the wrapper counts the run-time model's cycles");
        assert!(read_list(&mutant).contains("neo_bsu.v\n"));

        // A missing file: an error naming it.
        let missing = tmp.path().join("missing");
        write_bsu(&missing, str::to_string);
        std::fs::remove_file(missing.join("neo_cmp_swap.v")).unwrap();
        std::env::set_var("NEO_HDL_DIR", &missing);
        let Err(err) = std::panic::catch_unwind(NeoBsu::new) else {
            panic!("a missing file is an error");
        };
        let msg = err.downcast_ref::<String>().cloned().unwrap_or_default();
        assert!(msg.contains("neo_cmp_swap.v") && msg.contains("a file of neo_bsu"), "{msg}");
        std::env::remove_var("NEO_HDL_DIR");
    }
}
