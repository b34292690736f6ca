//! The engine's AXI4 memory clients: which unit is client `c`, and where each client sits on
//! the memory ports. The one definition of the numbering: gen wires the engine's client buses
//! by it, tb sums each port's outstanding limits and names a port's IDs by it, and sim's engine
//! model puts each core's traffic on its port by it.

use super::EngineConfig;
use std::fmt;

/// One AXI4 memory client of the engine. Clients are numbered in this order: the frame
/// controller, the sorting cores' bridges, the raster cores' bridges, then the Preprocessing
/// Engine's managers (every lane's geometry port, every lane's SH port, the list writer).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MemoryClient {
    /// The frame controller (descriptors, results, scratch): client 0.
    FrameController,
    /// Sorting core `i`'s bridge: client `1 + i`.
    SortCore(usize),
    /// Raster core `j`'s bridge: client `1 + N + j`.
    RasterCore(usize),
    /// Preprocessing lane `p`'s geometry and feature port: client `1 + N + M + p`.
    PreGeometry(usize),
    /// Preprocessing lane `p`'s SH and previous-feature port: client `1 + N + M + P + p`.
    PreSh(usize),
    /// The Preprocessing Engine's list writer: client `1 + N + M + 2 P`.
    PreListWriter,
}

impl MemoryClient {
    /// Whether the client is one of the Preprocessing Engine's managers.
    pub fn is_preprocessing(self) -> bool {
        matches!(self, MemoryClient::PreGeometry(_) | MemoryClient::PreSh(_) | MemoryClient::PreListWriter)
    }
}

impl fmt::Display for MemoryClient {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MemoryClient::FrameController => write!(f, "frame controller"),
            MemoryClient::SortCore(i) => write!(f, "sort core {i}"),
            MemoryClient::RasterCore(j) => write!(f, "raster core {j}"),
            MemoryClient::PreGeometry(p) => write!(f, "preprocessing lane {p} (geometry, features)"),
            MemoryClient::PreSh(p) => write!(f, "preprocessing lane {p} (SH, previous features)"),
            MemoryClient::PreListWriter => write!(f, "preprocessing list writer"),
        }
    }
}

impl EngineConfig {
    /// The engine's AXI4 memory clients: the frame controller, the sorting and raster cores'
    /// bridges, and the Preprocessing Engine's ([`EngineConfig::pre_managers`]).
    pub fn memory_clients(&self) -> usize {
        1 + self.sort_cores + self.raster_cores + self.pre_managers()
    }

    /// The index of `client` in the engine's client order ([`MemoryClient`]). The index of a
    /// unit the configuration does not have (a core past the last) is past its group.
    pub fn client_index(&self, client: MemoryClient) -> usize {
        let (n, m, p) = (self.sort_cores, self.raster_cores, self.pre_units);
        match client {
            MemoryClient::FrameController => 0,
            MemoryClient::SortCore(i) => 1 + i,
            MemoryClient::RasterCore(j) => 1 + n + j,
            MemoryClient::PreGeometry(q) => 1 + n + m + q,
            MemoryClient::PreSh(q) => 1 + n + m + p + q,
            MemoryClient::PreListWriter => 1 + n + m + 2 * p,
        }
    }

    /// Memory client `c`, or `None` past the last ([`EngineConfig::memory_clients`]).
    pub fn memory_client(&self, c: usize) -> Option<MemoryClient> {
        let (n, m, p) = (self.sort_cores, self.raster_cores, self.pre_units);
        let client = match c {
            0 => MemoryClient::FrameController,
            c if c <= n => MemoryClient::SortCore(c - 1),
            c if c <= n + m => MemoryClient::RasterCore(c - 1 - n),
            c if c >= self.memory_clients() => return None,
            c => match c - 1 - n - m {
                q if q < p => MemoryClient::PreGeometry(q),
                q if q < 2 * p => MemoryClient::PreSh(q - p),
                _ => MemoryClient::PreListWriter,
            },
        };
        Some(client)
    }

    /// Every memory client, in client order.
    pub fn memory_client_list(&self) -> Vec<MemoryClient> {
        (0..self.memory_clients()).filter_map(|c| self.memory_client(c)).collect()
    }

    /// The AXI4 port memory client `client` is on ([`client_port_slot`]).
    pub fn client_port(&self, client: MemoryClient) -> usize {
        self.client_port_slot(self.client_index(client)).0
    }

    /// Slots of each AXI4 port's mux ([`port_slots`] of this engine's clients and ports).
    pub fn port_slots(&self) -> usize {
        port_slots(self.memory_clients(), self.mem_channels)
    }

    /// Memory client `c`'s `(port, slot)` on this engine's `mem_channels` ports
    /// ([`client_port_slot`]).
    pub fn client_port_slot(&self, c: usize) -> (usize, usize) {
        client_port_slot(c, self.mem_channels)
    }

    /// The memory client in `slot` of `port` ([`port_slot_client`]).
    pub fn port_slot_client(&self, port: usize, slot: usize) -> usize {
        port_slot_client(port, slot, self.mem_channels)
    }
}

/// Where memory client `c` (in [`EngineConfig::memory_clients`] order) sits among `ports` AXI4
/// ports: `(port, slot)` = `(c mod ports, c div ports)`. The clients are dealt round the ports,
/// so each port's mux has `ceil(clients / ports)` slots and the ports' loads differ by one
/// client at most; the mux's downstream ID is the slot.
pub fn client_port_slot(c: usize, ports: usize) -> (usize, usize) {
    (c % ports, c / ports)
}

/// Slots of each port's mux when `clients` memory clients are dealt round `ports` ports
/// ([`client_port_slot`]): `ceil(clients / ports)`.
pub fn port_slots(clients: usize, ports: usize) -> usize {
    clients.div_ceil(ports)
}

/// The memory client in `slot` of `port` among `ports` ports: the inverse of
/// [`client_port_slot`] (a slot past the last client gives an index past it too).
pub fn port_slot_client(port: usize, slot: usize, ports: usize) -> usize {
    slot * ports + port
}

#[cfg(test)]
mod tests {
    use super::*;

    fn configs() -> Vec<EngineConfig> {
        let base = EngineConfig::default();
        [(16, 4, 4, 4), (2, 1, 1, 2), (1, 1, 0, 1), (3, 2, 2, 4), (16, 4, 16, 1)]
            .into_iter()
            .map(|(sort_cores, raster_cores, pre_units, mem_channels)| EngineConfig {
                sort_cores,
                raster_cores,
                pre_units,
                mem_channels,
                ..base.clone()
            })
            .collect()
    }

    #[test]
    fn every_index_names_one_client_and_back() {
        for cfg in configs() {
            let list = cfg.memory_client_list();
            assert_eq!(list.len(), cfg.memory_clients());
            for (c, &client) in list.iter().enumerate() {
                assert_eq!(cfg.client_index(client), c, "{client}");
                assert_eq!(client.is_preprocessing(), c > cfg.sort_cores + cfg.raster_cores);
            }
            assert_eq!(cfg.memory_client(cfg.memory_clients()), None);
            let cores = list.iter().filter(|c| matches!(c, MemoryClient::SortCore(_))).count();
            assert_eq!(cores, cfg.sort_cores);
            let pre = list.iter().filter(|c| c.is_preprocessing()).count();
            assert_eq!(pre, cfg.pre_managers());
        }
    }

    #[test]
    fn names_say_which_unit() {
        let cfg = EngineConfig { pre_units: 2, ..EngineConfig::default() };
        let names: Vec<String> = cfg.memory_client_list().iter().map(|c| c.to_string()).collect();
        assert_eq!(names[0], "frame controller");
        assert_eq!(names[1], "sort core 0");
        assert_eq!(names[1 + cfg.sort_cores], "raster core 0");
        let pre = 1 + cfg.sort_cores + cfg.raster_cores;
        assert_eq!(names[pre + 1], "preprocessing lane 1 (geometry, features)");
        assert_eq!(names[pre + 2], "preprocessing lane 0 (SH, previous features)");
        assert_eq!(names.last().unwrap(), "preprocessing list writer");
    }
}
