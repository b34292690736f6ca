//! The port mux `neo_axi_mux` at a chosen `PORTS`, as a model the AXI bench drives client by
//! client: a wrapper top `neo_axi_mux_tb_p<P>` instantiates `neo_axi_mux #(.PORTS(P))` and
//! gives each client's signals their own ports (`s<i>_axi_*`, bound with
//! [`super::AxiBinding`]), the client buses being concatenations of them; the manager port
//! `m_axi_*` passes through. The wrapper is only wiring: the mux's behaviour is the module's.

use crate::dynmodel::DynModel;
use neo_gen::emit::Module;
use neo_gen::units::axi::{self, mux};
use neo_gen::EngineConfig;

/// The wrapper of `neo_axi_mux` at `ports` clients for `cfg`.
///
/// # Errors
/// When `ports` clients do not fit `cfg`'s AXI IDs ([`mux::check`]).
pub fn wrapper(cfg: &EngineConfig, ports: usize) -> Result<Module, String> {
    mux::check(cfg, ports).map_err(|e| e.to_string())?;
    let mut m = Module::new(format!("{}_tb_p{ports}", mux::NAME));
    m.doc(format!(
        "Bench wrapper: {} #(.PORTS({ports})), each client's signals as ports s<i>_axi_*.",
        mux::NAME
    ));
    m.clock_reset();
    for i in 0..ports {
        axi::ports(&mut m, cfg, &format!("s{i}_axi_"), false);
    }
    axi::ports(&mut m, cfg, "m_axi_", true);
    let mut conns = vec![("clk_i".to_string(), "clk_i".to_string()), ("rst_ni".into(), "rst_ni".into())];
    for sig in axi::signals(cfg) {
        let clients: Vec<String> =
            (0..ports).rev().map(|i| axi::port_name(&format!("s{i}_axi_"), &sig, false)).collect();
        conns.push((mux::client_port(&sig), format!("{{{}}}", clients.join(", "))));
    }
    for sig in axi::signals(cfg) {
        let p = axi::port_name("m_axi_", &sig, true);
        conns.push((p.clone(), p));
    }
    m.instance_with(mux::NAME, "u_mux", vec![("PORTS".into(), ports.to_string())], conns);
    Ok(m)
}

/// Builds (or loads from the cache) the model of [`wrapper`]: `neo_axi_mux.v` as generated for
/// `cfg` (or `$NEO_HDL_DIR`'s copy: [`crate::dynmodel::generated_files`]) and the wrapper,
/// traced in the format `WAVES` asks for (untraced without it).
///
/// # Errors
/// When the clients do not fit the IDs or the model does not build.
pub fn build(cfg: &EngineConfig, ports: usize) -> Result<DynModel, String> {
    let top = wrapper(cfg, ports)?;
    let (mut files, vlt) = crate::dynmodel::generated_files(cfg, mux::NAME)?;
    files.push((format!("{}.v", top.name), top.to_verilog()));
    let format = crate::waves::try_requested_format()?;
    let (model, _) = DynModel::build_traced(&top.interface(), &files, Some(&vlt), format)?;
    Ok(model)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wrapper_names_every_client_and_concatenates_the_buses() {
        let cfg = EngineConfig::default();
        let v = wrapper(&cfg, 3).expect("3 clients fit 4 ID bits").to_verilog();
        assert!(v.contains("  neo_axi_mux #(\n    .PORTS(3)\n  ) u_mux (\n"), "{v}");
        assert!(v.contains(".s_axi_araddr_i({s2_axi_araddr_i, s1_axi_araddr_i, s0_axi_araddr_i})"), "{v}");
        assert!(v.contains(".m_axi_rdata_i(m_axi_rdata_i)"), "{v}");
        let narrow = EngineConfig { axi_id_bits: 2, ..cfg };
        assert!(wrapper(&narrow, 4).is_ok());
        assert!(wrapper(&narrow, 5).unwrap_err().contains("axi_id_bits is 2"));
    }
}
