//! Every engine configuration that validation accepts generates: the emitter never panics on
//! it (a limit the generator has is a validation error naming the field, `neo gen --config`).

use neo_gen::SchedulerPolicy;
use neo_gen::{try_generate, EngineConfig};
use proptest::prelude::*;

/// Values tried for field `field` of [`apply`]: each end of its documented range, its
/// neighbours outside and values inside (powers of two and theirs).
fn values(field: usize) -> Vec<u64> {
    const P31: u64 = 1 << 31;
    const P48: u64 = 1 << 48;
    match field {
        0 => vec![7, 8, 9, 12, 16, 17, 20, 24, 31, 32, 33, 40, 47, 48, 49],
        1 => vec![11, 12, 13, 16, 17, 24, 31, 32, 33, 40, 48, 49],
        2 | 3 => vec![0, 1, 2, 8, 15, 16, 17, 24, 31, 32, 33, 40, 48],
        4 => vec![255, 256, 257, 1024, 65535, 65536, 65537, 1 << 20, P31 - 1, P31, 1 << 32, P48 - 1, P48],
        5 => vec![16, 32, 64, 128, 256, 512, 1024, 4096, 65536, 65537],
        6 => vec![32, 63, 64, 65, 128, 256, 512, 1024, 2048],
        7 => vec![31, 32, 33, 40, 48, 63, 64, 65],
        8 => vec![0, 1, 2, 3, 4, 8, 15, 16, 17],
        9 => vec![0, 1, 2, 3, 4, 8, 16, 32, 64, 65, 128],
        10 => vec![0, 1, 2, 3, 4, 5, 8, 15, 16, 17],
        11 => vec![0, 1, 2, 3, 4, 8, 16, 17, 32],
        12 => vec![0, 1, 2, 4, 8, 16, 64, 128, 256, 512, 1024, 2048],
        13 => vec![0, 1, 2, 4, 8, 16, 64, 128, 256, 512],
        14 => vec![1, 2, 3, 4, 16, 1024, 2048, 65536, 65537, 131072],
        15 => vec![0, 1, 2, 3, 4, 16, 32, 63, 64, 65],
        16 => vec![0, 1, 2, 3, 4, 8, 15, 16, 17],
        17 => vec![0, 1, 2, 4, 8, 10, 15, 16, 17],
        18 => vec![0, 1, 2, 8, 16, 32, 63, 64, 65],
        _ => vec![0, 1, 2, 4, 8, 16, 32, 64, 256, 257],
    }
}

/// One field of the default configuration and a value for it ([`values`]).
fn one_change() -> impl Strategy<Value = (usize, u64)> {
    (0usize..FIELDS).prop_flat_map(|f| (Just(f), prop::sample::select(values(f))))
}

/// Fields [`apply`] changes.
const FIELDS: usize = 20;

/// `cfg` with field `field` set to `v` (saturated to the field's type).
fn apply(cfg: &mut EngineConfig, field: usize, v: u64) {
    let (u8v, u32v, us) = (v.min(255) as u8, v.min(u32::MAX as u64) as u32, v as usize);
    match field {
        0 => cfg.addr_bits = u32v,
        1 => cfg.len_bits = u32v,
        2 => cfg.key_bits = u8v,
        3 => cfg.id_bits = u8v,
        4 => cfg.table_capacity = us,
        5 => cfg.chunk = us,
        6 => cfg.axi_data_bits = u32v,
        7 => cfg.axi_addr_bits = u32v,
        8 => cfg.axi_id_bits = u32v,
        9 => cfg.axi_outstanding = us,
        10 => cfg.mem_channels = us,
        11 => cfg.pre_units = us,
        12 => cfg.pre_read_lines = us,
        13 => cfg.pre_outstanding = us,
        14 => cfg.pre_max_tiles = us,
        15 => cfg.sort_cores = us,
        16 => cfg.raster_cores = us,
        17 => cfg.tile_bits = u32v,
        18 => cfg.itu_tag_bits = u32v,
        _ => cfg.burst = us,
    }
}

/// The default configuration with one to three fields changed ([`one_change`]), round-robin
/// scheduling or not.
fn config() -> impl Strategy<Value = EngineConfig> {
    (prop::collection::vec(one_change(), 1..=3), any::<bool>()).prop_map(|(changes, round_robin)| {
        let mut cfg = EngineConfig::default();
        for (field, v) in changes {
            apply(&mut cfg, field, v);
        }
        if round_robin {
            cfg.scheduler = SchedulerPolicy::RoundRobin;
        }
        cfg
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, max_global_rejects: 4096, ..ProptestConfig::default() })]

    /// Validation and generation agree: an accepted configuration generates without a panic.
    #[test]
    fn every_accepted_configuration_generates(cfg in config()) {
        prop_assume!(cfg.validate().is_ok());
        prop_assert!(try_generate(&cfg).is_ok());
    }
}

/// Configurations `neo gen --config` once panicked on, one or two fields changed from the
/// default: each is now rejected by validation naming its field (`Some(field)`), or generates
/// (`None`: a 64-bit entry fills the list writer's 64-bit slot).
#[test]
fn configurations_that_panicked_are_rejected_naming_their_field_or_generate() {
    let base = EngineConfig::default();
    let cases = [
        (Some("axi_data_bits"), EngineConfig { axi_data_bits: 128, ..base.clone() }),
        (Some("axi_data_bits"), EngineConfig { axi_data_bits: 1024, ..base.clone() }),
        (Some("addr_bits"), EngineConfig { addr_bits: 8, ..base.clone() }),
        (Some("addr_bits"), EngineConfig { addr_bits: 17, ..base.clone() }),
        (Some("table_capacity"), EngineConfig { table_capacity: 1 << 31, ..base.clone() }),
        (
            Some("table_capacity"),
            EngineConfig { len_bits: 48, table_capacity: (1 << 48) - 1, ..base.clone() },
        ),
        (None, EngineConfig { key_bits: 32, ..base.clone() }),
    ];
    for (field, cfg) in cases {
        match (field, cfg.validate()) {
            (Some(field), Err(e)) => assert!(e.0.contains(field), "{field}: {e}"),
            (Some(field), Ok(())) => panic!("{field}: accepted {cfg:?}"),
            (None, Ok(())) => assert!(try_generate(&cfg).is_ok(), "{cfg:?}"),
            (None, Err(e)) => panic!("rejected {cfg:?}: {e}"),
        }
    }
}
