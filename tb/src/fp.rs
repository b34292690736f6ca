//! The binary32 primitives' bench (`neo_fp_bench`: every `neo_fp_*` primitive side by side,
//! built at run time as one Verilator model): operands pushed every enabled cycle, every
//! primitive's `y_o` checked bit for bit against golden `hwarith::Native` exactly
//! `latency(p)` enabled cycles later (cycles with `en_i` low in between), the combinational
//! `neo_fp_cmp` checked every cycle, and the latency measured.

use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::rng::Rng;
use neo_gen::units::fp::{bench, label, latency, FpPrim};
use neo_golden::hwarith::graph::{eval_op, Op, Ty};

/// Number of pipelined primitives.
const NP: usize = FpPrim::ALL.len();

/// One operation: operands and the name of the class it belongs to (printed on a mismatch).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Vector {
    /// Operand a (bits; an integer for `from_int`, half bits for `widen_half`).
    pub a: u32,
    /// Operand b (bits).
    pub b: u32,
    /// The stimulus class (`random`, or a directed class name).
    pub class: &'static str,
}

/// Golden result of primitive `p` on operand bits `a`, `b`: `Native`'s (whose arithmetic
/// returns the canonical NaN, checked on the bits).
pub fn expected(p: FpPrim, a: u32, b: u32) -> u32 {
    native(p, a, b)
}

/// The graph operation primitive `p` implements, on operands `a` (node 0) and `b` (node 1),
/// and its result type: the inverse of the datapath library's lowering of an [`Op`] to a
/// primitive (`gen/src/units/pre/library.rs`; the `fp` tests check the round trip).
pub fn op(p: FpPrim) -> (Op, Ty) {
    match p {
        FpPrim::Add => (Op::Add(0, 1), Ty::F),
        FpPrim::Sub => (Op::Sub(0, 1), Ty::F),
        FpPrim::Mul => (Op::Mul(0, 1), Ty::F),
        FpPrim::Div => (Op::Div(0, 1), Ty::F),
        FpPrim::Sqrt => (Op::Sqrt(0), Ty::F),
        FpPrim::ToInt(mode) => (Op::ToInt(0, mode), Ty::I),
        FpPrim::FromInt => (Op::IntToFloat(0), Ty::F),
        FpPrim::F16 => (Op::F16Bits(0), Ty::I),
        FpPrim::WidenHalf => (Op::WidenHalf(0), Ty::F),
    }
}

/// `Native`'s result of primitive `p` on operand bits `a`, `b`: golden's evaluation of the
/// graph operation ([`eval_op`]), the same code [`neo_golden::hwarith::graph::Graph::eval`] runs.
pub fn native(p: FpPrim, a: u32, b: u32) -> u32 {
    let (op, ty) = op(p);
    eval_op(&op, ty, &[a, b], &[])
}

/// The outputs of `neo_fp_cmp` (`lt_o`, `le_o`, `eq_o`, `max_o`, `min_o`) as graph operations on
/// `a` (node 0) and `b` (node 1), with their result types.
pub const CMP_OPS: [(Op, Ty); 5] = [
    (Op::Lt(0, 1), Ty::B),
    (Op::Le(0, 1), Ty::B),
    (Op::Eq(0, 1), Ty::B),
    (Op::Max(0, 1), Ty::F),
    (Op::Min(0, 1), Ty::F),
];

/// Golden `(lt, le, eq, max, min)` of `a`, `b` ([`CMP_OPS`] through [`eval_op`]).
pub fn expected_cmp(a: u32, b: u32) -> (bool, bool, bool, u32, u32) {
    let [lt, le, eq, max, min] = CMP_OPS.map(|(op, ty)| eval_op(&op, ty, &[a, b], &[]));
    (lt != 0, le != 0, eq != 0, max, min)
}

/// The verilated `neo_fp_bench` and its port indices.
pub struct FpBench {
    /// The model.
    pub model: DynModel,
    en: usize,
    a: usize,
    b: usize,
    y: Vec<(FpPrim, usize)>,
    cmp: [usize; 5],
    widen_comb: usize,
}

/// Counts of a checked run.
#[derive(Clone, Copy, Debug, Default)]
pub struct FpRun {
    /// Operations presented (each checked on every primitive).
    pub ops: u64,
    /// Clock cycles (stalls included).
    pub cycles: u64,
}

impl FpBench {
    /// Generates `neo_fp_bench` (default configuration), verilates and compiles it (or finds it
    /// in the cache) and loads it; traced when `WAVES` asks for it. With `NEO_HDL_DIR=DIR`, `DIR`'s
    /// copies of its files and `DIR/lint.vlt` ([`crate::dynmodel::generated_files`]).
    pub fn build() -> Result<FpBench, String> {
        let cfg = neo_gen::EngineConfig::default();
        let (files, vlt) = crate::dynmodel::generated_files(&cfg, bench::NAME)?;
        let iface = crate::dynmodel::generated_interface(&cfg, bench::NAME)?;
        let format = crate::waves::requested_format();
        let (model, info) = DynModel::build_traced(&iface, &files, Some(&vlt), format)?;
        if !info.cached {
            println!("neo_fp_bench built in {:.1} s: {}", info.seconds, info.log);
        }
        let port = |n: &str| model.port(n);
        let y =
            FpPrim::ALL.iter().map(|&p| Ok((p, port(&bench::port(p))?))).collect::<Result<_, String>>()?;
        let cmp = [port("lt_o")?, port("le_o")?, port("eq_o")?, port("max_o")?, port("min_o")?];
        let widen_comb = port(bench::WIDEN_COMB_PORT)?;
        Ok(FpBench { en: port("en_i")?, a: port("a_i")?, b: port("b_i")?, y, cmp, widen_comb, model })
    }

    fn drive(&mut self, en: bool, a: u32, b: u32) {
        self.model.set_u64(self.en, en as u64);
        self.model.set_u64(self.a, a as u64);
        self.model.set_u64(self.b, b as u64);
        self.model.eval();
    }

    /// Checks the combinational modules (`neo_fp_cmp`, `neo_fp_widen_half_comb`) on the operands
    /// driven now.
    fn check_combinational(&self, seed: u64, a: u32, b: u32, class: &str) {
        let (want, got) = (expected(FpPrim::WidenHalf, a, b), self.model.get_u64(self.widen_comb) as u32);
        if got != want {
            Checker::new("neo_fp_widen_half_comb", seed).fail(
                self.model.cycle(),
                &format!("y_o (class {class}, a 0x{a:08x})"),
                &format!("0x{want:08x}"),
                &format!("0x{got:08x}"),
            );
        }
        let (lt, le, eq, max, min) = expected_cmp(a, b);
        let want = [lt as u64, le as u64, eq as u64, max as u64, min as u64];
        for (k, field) in ["lt_o", "le_o", "eq_o", "max_o", "min_o"].iter().enumerate() {
            let got = self.model.get_u64(self.cmp[k]);
            if got != want[k] {
                Checker::new("neo_fp_cmp", seed).fail(
                    self.model.cycle(),
                    &format!("{field} (class {class}, a 0x{a:08x}, b 0x{b:08x})"),
                    &format!("0x{:x}", want[k]),
                    &format!("0x{got:x}"),
                );
            }
        }
    }

    /// Presents `vectors` one per enabled cycle, with `en_i` low for a random run of cycles
    /// before an operation with probability `stall_pct`%, then drains the pipelines. After
    /// every clock edge each primitive's `y_o` must be the golden result of the operation
    /// presented `latency(p)` enabled cycles before (so results hold while `en_i` is low), and
    /// the combinational modules' that of the operands driven. Panics at the first mismatch.
    pub fn run_checked(&mut self, seed: u64, vectors: &[Vector], stall_pct: u32) -> FpRun {
        const RING: usize = 64;
        let max_l = FpPrim::ALL.iter().map(|&p| latency(p)).max().unwrap_or(0) as usize;
        assert!(max_l < RING);
        let mut rng = Rng::new(seed ^ 0xf9_5eed);
        // Per enabled cycle: the vector, its index and every primitive's expected result.
        let mut ring: Vec<(Vector, usize, [u32; NP])> =
            vec![(Vector { a: 0, b: 0, class: "" }, 0, [0; NP]); RING];
        let (mut c, start) = (0usize, self.model.cycle());
        let total = vectors.len() + max_l;
        for i in 0..total {
            while stall_pct > 0 && rng.percent(stall_pct) {
                let (a, b) = (rng.next_u32(), rng.next_u32());
                self.drive(false, a, b);
                self.check_combinational(seed, a, b, "stall");
                self.model.tick();
                self.check_outputs(seed, &ring, c);
            }
            let v = match vectors.get(i) {
                Some(v) => *v,
                None => Vector { a: rng.next_u32(), b: rng.next_u32(), class: "drain" },
            };
            let mut want = [0u32; NP];
            for (k, &p) in FpPrim::ALL.iter().enumerate() {
                want[k] = expected(p, v.a, v.b);
            }
            ring[c % RING] = (v, i, want);
            self.drive(true, v.a, v.b);
            self.check_combinational(seed, v.a, v.b, v.class);
            self.model.tick();
            c += 1;
            self.check_outputs(seed, &ring, c);
        }
        FpRun { ops: vectors.len() as u64, cycles: self.model.cycle() - start }
    }

    /// After `c` enabled edges: primitive `p` shows the operation of enabled edge `c - L`.
    fn check_outputs(&self, seed: u64, ring: &[(Vector, usize, [u32; NP])], c: usize) {
        for (k, &(p, port)) in self.y.iter().enumerate() {
            let l = latency(p) as usize;
            if c < l {
                continue;
            }
            let (v, i, want) = &ring[(c - l) % ring.len()];
            let got = self.model.get_u64(port) as u32;
            if got != want[k] {
                Checker::new(&label(p), seed).fail(
                    self.model.cycle(),
                    &format!(
                        "y_o (vector {i}, class {}, a 0x{:08x}, b 0x{:08x}, latency {l})",
                        v.class, v.a, v.b
                    ),
                    &format!("0x{:08x}", want[k]),
                    &format!("0x{got:08x}"),
                );
            }
        }
    }

    /// Measures each primitive's latency: random operations every cycle (`en_i` high), the
    /// outputs recorded after each edge; the latency is the smallest `L` for which every
    /// recorded output from edge 40 on is the golden result of the operation `L` edges
    /// earlier (`None` when no `L < 40` fits: wrong results, or not one operation per cycle).
    pub fn measure_latencies(&mut self, seed: u64) -> Vec<(FpPrim, Option<u32>)> {
        const N: usize = 96;
        const FROM: usize = 40;
        let mut rng = Rng::new(seed);
        let ops: Vec<(u32, u32)> = (0..N).map(|_| structured_pair(&mut rng)).collect();
        let mut outs = vec![[0u32; NP]; N];
        for (t, &(a, b)) in ops.iter().enumerate() {
            self.drive(true, a, b);
            self.model.tick();
            for (k, &(_, port)) in self.y.iter().enumerate() {
                outs[t][k] = self.model.get_u64(port) as u32;
            }
        }
        // outs[t] is after edge t + 1: operation t + 1 - L.
        FpPrim::ALL
            .iter()
            .enumerate()
            .map(|(k, &p)| {
                let fits = |l: usize| {
                    (FROM..N).all(|t| outs[t][k] == expected(p, ops[t + 1 - l].0, ops[t + 1 - l].1))
                };
                (p, (1..FROM).find(|&l| fits(l)).map(|l| l as u32))
            })
            .collect()
    }
}

/// A random operand: uniform bits, or a structured value (an exponent drawn from the
/// interesting ones, a mantissa from patterns), or an integer of random bit length.
pub fn structured(rng: &mut Rng) -> u32 {
    let sign = rng.next_u32() & 0x8000_0000;
    let exp = match rng.below(10) {
        0 => 0,
        1 => 255,
        2 => *rng.pick(&[1u32, 2, 254, 253, 127, 126, 128]),
        3 => rng.range(0, 30) as u32,
        4 => rng.range(100, 160) as u32,
        5 => rng.range(225, 255) as u32,
        6 => return rng.next_u32() >> rng.below(32),
        7 => return (rng.next_u32() >> rng.below(32)).wrapping_neg(),
        _ => rng.range(0, 255) as u32,
    };
    let mant = match rng.below(8) {
        0 => 0,
        1 => 0x7F_FFFF,
        2 => 1 << rng.below(23),
        3 => 0x7F_FFFF ^ (1 << rng.below(23)),
        4 => rng.next_u32() & 0x7F_FFFF & !((1 << rng.below(23)) - 1),
        5 => (rng.next_u32() & 0x7F_FFFF) >> rng.below(23),
        _ => rng.next_u32() & 0x7F_FFFF,
    };
    sign | exp << 23 | mant
}

/// A random operand pair: uniform bits (a quarter), or structured operands, b often close to
/// a (near exponents, near significands: alignment, cancellation and rounding cases).
pub fn structured_pair(rng: &mut Rng) -> (u32, u32) {
    if rng.percent(25) {
        return (rng.next_u32(), rng.next_u32());
    }
    let a = structured(rng);
    let b = match rng.below(4) {
        0 => {
            // Near exponent, random significand.
            let e = ((a >> 23) & 0xFF) as i64 + rng.range(0, 60) as i64 - 30;
            (rng.next_u32() & 0x807F_FFFF) | (e.clamp(0, 255) as u32) << 23
        }
        1 => {
            // Near value (cancellation): a few ulps away, either sign.
            let d = rng.range(0, 8) as u32;
            let v = if rng.percent(50) { a.wrapping_add(d) } else { a.wrapping_sub(d) };
            v ^ ((rng.next_u32() & 1) << 31)
        }
        _ => structured(rng),
    };
    (a, b)
}

/// `n` random vectors (class `random`).
pub fn random_vectors(rng: &mut Rng, n: usize) -> Vec<Vector> {
    (0..n)
        .map(|_| {
            let (a, b) = structured_pair(rng);
            Vector { a, b, class: "random" }
        })
        .collect()
}

const P0: u32 = 0x0000_0000;
const N0: u32 = 0x8000_0000;
const MIN_SUB: u32 = 0x0000_0001;
const MAX_SUB: u32 = 0x007F_FFFF;
const MIN_NORM: u32 = 0x0080_0000;
const MAX_NORM: u32 = 0x7F7F_FFFF;
const INF: u32 = 0x7F80_0000;
const ONE: u32 = 0x3F80_0000;
const TWO: u32 = 0x4000_0000;
const HALF: u32 = 0x3F00_0000;

fn f(v: f32) -> u32 {
    v.to_bits()
}

/// The directed classes, each a list of operand pairs (every pair is checked on every
/// primitive; the class names what it is aimed at).
pub fn directed() -> Vec<(&'static str, Vec<(u32, u32)>)> {
    let neg = |x: u32| x ^ 0x8000_0000;
    let nans = [0x7FC0_0000, 0x7FC0_0001, 0xFFC1_2345, 0x7F80_0001, 0xFFFF_FFFF, 0x7FBF_FFFF];
    let specials: Vec<u32> = {
        let pos = [
            P0,
            MIN_SUB,
            0x0000_0003,
            MAX_SUB,
            0x0040_0000,
            MIN_NORM,
            0x0080_0001,
            ONE,
            f(1.5),
            TWO,
            f(3.0),
            HALF,
            f(1.0 / 3.0),
            MAX_NORM,
            0x7F00_0000,
            INF,
            0x4F00_0000,
            0x4EFF_FFFF,
            0x1F80_0000,
            0x207F_FFFF,
            f(65504.0),
            f(65520.0),
        ];
        let mut v: Vec<u32> = pos.iter().flat_map(|&x| [x, neg(x)]).collect();
        v.extend(nans);
        v
    };
    let cross = |xs: &[u32], ys: &[u32]| -> Vec<(u32, u32)> {
        xs.iter().flat_map(|&a| ys.iter().map(move |&b| (a, b))).collect()
    };
    let one_eps = |k: u32| ONE + k; // 1 + k ulp
    vec![
        ("signed zeros", cross(&[P0, N0], &[P0, N0, ONE, neg(ONE), MIN_SUB, neg(MIN_SUB)])),
        (
            "subnormals (smallest, largest)",
            cross(
                &[MIN_SUB, MAX_SUB, neg(MIN_SUB), neg(MAX_SUB)],
                &[MIN_SUB, MAX_SUB, neg(MAX_SUB), ONE, TWO, HALF],
            ),
        ),
        (
            "smallest and largest normal",
            cross(
                &[MIN_NORM, MAX_NORM, neg(MIN_NORM), neg(MAX_NORM)],
                &[MIN_NORM, MAX_NORM, neg(MAX_NORM), ONE, HALF],
            ),
        ),
        ("infinities", cross(&[INF, neg(INF)], &[INF, neg(INF), P0, N0, ONE, neg(MIN_SUB), MAX_NORM])),
        ("NaNs with payloads", cross(&nans, &[ONE, INF, P0, 0xFFC0_0000, 0x7F80_0001])),
        (
            "results that round to a tie",
            vec![
                (ONE, 0x3380_0000),         // 1 + 2^-24: tie, stays 1
                (one_eps(1), 0x3380_0000),  // (1 + 2^-23) + 2^-24: tie, rounds up
                (0x3F80_0800, 0x3F80_0800), // (1 + 2^-12)^2 = 1 + 2^-11 + 2^-24
                (0x3F80_1800, 0x3F80_0800), // (1 + 3 2^-12)(1 + 2^-12): tie, rounds to even
                (0x0000_0003, TWO),         // 3 2^-149 / 2: subnormal tie
                (0x0000_0005, TWO),
                (16_777_217, 0), // int_to_float tie (2^24 + 1)
                (16_777_219, 0),
                (0x3F80_1000, 0), // f16 tie: 1 + 2^-11
                (0x3F80_3000, 0), // f16 tie, rounds up
                (0x3300_0000, 0), // f16: 2^-25, tie to zero
                (0x3340_0000, 0), // f16: 1.5 2^-25
            ],
        ),
        (
            "results overflowing to inf",
            vec![
                (MAX_NORM, TWO),
                (MAX_NORM, MAX_NORM),
                (MAX_NORM, HALF),
                (0x7F00_0000, 0x4000_0000),
                (neg(MAX_NORM), neg(MAX_NORM)),
                (MAX_NORM, 0x7380_0000), // max + 2^104: rounds up to inf
                (MAX_NORM, 0x7300_0000), // max + 2^103: a tie, stays max (even)
                (MAX_NORM, MIN_NORM),    // max / min_normal
            ],
        ),
        (
            "results underflowing into subnormal and to zero",
            vec![
                (0x0D80_0000, 0x1080_0000), // 2^-100 * 2^-30
                (MIN_NORM, TWO),            // min_normal / 2 and * 2
                (MIN_NORM, HALF),
                (0x0D80_0000, 0x0D80_0000),   // 2^-100 * 2^-100: zero
                (MIN_SUB, HALF),              // tie to zero
                (MIN_SUB, f(0.75)),           // rounds up to min_sub
                (MIN_SUB, f(3.0)),            // min_sub / 3 -> 0
                (MIN_SUB, f(1.5)),            // min_sub / 1.5 -> rounds to min_sub
                (0x0080_0001, neg(MIN_NORM)), // cancellation to a subnormal
                (MAX_NORM, 0x0000_0002),
            ],
        ),
        (
            "rounding from subnormal up to the smallest normal",
            vec![
                (MAX_SUB, MIN_SUB),         // max_sub + min_sub = min_normal
                (MAX_SUB, one_eps(1)),      // max_sub (1 + 2^-23): rounds up to min_normal
                (0x1F80_0000, 0x207F_FFFF), // 2^-64 * (2 - 2^-23) 2^-63: tie up to min_normal
                (0x1F80_0000, 0x207F_FFFE),
                (MIN_NORM, one_eps(1)), // min_normal / (1 + 2^-23): just below
                (MAX_SUB, 0x3F7F_FFFF), // max_sub / (1 - 2^-24)
            ],
        ),
        (
            "sqrt of negatives",
            vec![
                (neg(ONE), 0),
                (neg(MIN_SUB), 0),
                (neg(INF), 0),
                (N0, 0),
                (neg(MAX_NORM), 0),
                (0xFFC0_0001, 0),
            ],
        ),
        ("division by zero and 0/0", cross(&[ONE, neg(ONE), P0, N0, MIN_SUB, INF], &[P0, N0])),
        (
            "to_int at +-2^31",
            [0x4F00_0000, 0x4EFF_FFFF, 0x4F00_0001, 0x4F80_0000]
                .iter()
                .flat_map(|&x| [(x, 0), (neg(x), 0)])
                .collect(),
        ),
        (
            "to_int at .5 boundaries",
            [
                HALF,
                f(1.5),
                f(2.5),
                0x3EFF_FFFF,
                0x3F00_0001,
                0x4AFF_FFFF,
                0x4B00_0000,
                one_eps(1),
                0x3F7F_FFFF,
                MIN_SUB,
                f(-0.0),
                0x4EFF_FFFE,
                f(3.5),
                f(1e-30),
                0x3E80_0000,
            ]
            .iter()
            .flat_map(|&x| [(x, 0), (neg(x), 0)])
            .collect(),
        ),
        (
            "int_to_float of values above 2^24",
            [
                16_777_217u32,
                16_777_219,
                33_554_435,
                0x7FFF_FFFF,
                0x7FFF_FFC0,
                0x7FFF_FF80,
                0x0100_0001,
                0x4000_0041,
            ]
            .iter()
            .flat_map(|&x| [(x, 0), (x.wrapping_neg(), 0)])
            .chain([(0x8000_0000, 0), (0, 0), (1, 0), (0xFFFF_FFFF, 0)])
            .collect(),
        ),
        (
            "widen_half: every half",
            (0..=0xFFFFu32).map(|h| (h | (h.wrapping_mul(0x9E37) << 16), 0)).collect(),
        ),
        (
            "f16_bits boundaries",
            [
                f(65504.0),
                f(65519.0),
                f(65520.0),
                f(65536.0),
                0x3380_0000,
                0x3380_0001,
                0x337F_FFFF,
                f(6.097555e-5),
                0x3880_0000,
                0x387F_FFFF,
                0x387F_E000,
                0x387F_F000,
                MIN_NORM,
                MAX_SUB,
                0x4780_0000,
                0x477F_F000,
            ]
            .iter()
            .flat_map(|&x| [(x, 0), (neg(x), 0)])
            .collect(),
        ),
        ("special values x special values", cross(&specials, &specials)),
    ]
}

/// [`directed`] as one list of vectors, class by class.
pub fn directed_vectors() -> Vec<Vector> {
    directed()
        .into_iter()
        .flat_map(|(class, pairs)| pairs.into_iter().map(move |(a, b)| Vector { a, b, class }))
        .collect()
}
