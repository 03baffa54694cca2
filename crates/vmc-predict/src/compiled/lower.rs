//! Lowering a [`HybridPredictor`] to its compiled form: the model file's parts (linear models,
//! regressors) split into temperature and position columns and packed (layouts in `temps` and
//! `query`), the chain folded into signs and arm masks.
//!
//! The split is done here again from the parts, not taken from the library's query-path
//! evaluators, so the compiled form is an independent reading of the model file.

use crate::nn::{Activation, Regressor};
use crate::predictor::{ErrorPredictor, HybridPredictor, LinearPlusNet};
use crate::synthesis::{LinearAxis, MachineGeometry};

use super::query::{AxisHead, Isa, UnitBlock, N_OUT};
use super::temps::{Inputs, PartCoefficients, SpindleStage, SquarenessStage, TempPart};
use super::{CompileError, CompiledHybrid, Synthesis};

/// Network names, as in the model's training summary.
const AXIS_NETS: [&str; 3] = ["axis_x", "axis_y", "axis_z"];

/// What a query needs of a part's net: the position column of the first layer, the output
/// layer and the normalisations of the position and the outputs.
#[derive(Debug, Clone, Default)]
struct QueryNet {
    hidden: usize,
    /// First-layer weight of the position, per unit (empty for the spindle).
    w_pos: Vec<f64>,
    /// Output layer, row-major `n_out × H`.
    w2: Vec<f64>,
    b2: Vec<f64>,
    out_std: Vec<f64>,
    out_mean: Vec<f64>,
    pos_mean: f64,
    pos_std: f64,
}

/// Compiles `p` (see [`CompiledHybrid::from_predictor`]).
pub(super) fn lower(p: &HybridPredictor) -> Result<CompiledHybrid, CompileError> {
    let parts = p.parts();
    let inputs = Inputs::new(p.filter_state(), parts.axis_feed_own_axis);
    let (n_axis_t, n_all_t) = inputs.widths();
    let mut axis_temps = Vec::with_capacity(3);
    let mut nets = Vec::with_capacity(3);
    for (part, name) in parts.axis_nets.iter().zip(AXIS_NETS) {
        let (coef, net) = split_part(part, 1, n_axis_t, N_OUT, name)?;
        axis_temps.push(TempPart::pack(&coef));
        nets.push(net.unwrap_or_default());
    }
    let (coef, net) = split_part(&parts.spindle_net, 0, n_all_t, 5, "spindle")?;
    let net = net.unwrap_or_default();
    let mut head = net.w2.clone();
    if net.hidden > 0 {
        head.extend(net.b2.iter().chain(&net.out_std).chain(&net.out_mean));
    }
    let spindle = SpindleStage {
        part: TempPart::pack(&coef),
        hidden: net.hidden,
        head: head.into_boxed_slice(),
        scratch: vec![0.0; 2 * net.hidden].into_boxed_slice(),
    };
    let sq = &parts.squareness;
    let n_shared = inputs.n_shared();
    if sq.n_in() != n_shared || sq.n_out() != 3 || n_shared == 0 {
        return Err(CompileError::Inconsistent {
            reason: format!(
                "the squareness maps {} → {} values; expected {n_shared} (≥ 1) → 3",
                sq.n_in(),
                sq.n_out()
            ),
        });
    }
    let squareness = SquarenessStage {
        n_in: n_shared,
        data: sq.intercept().iter().chain(sq.slopes()).copied().collect(),
    };
    let synthesis = synthesis_of(p.geometry());
    let (heads, units) = pack_axes(&nets, synthesis.sign);
    let max_hidden = heads.iter().map(|a| a.hidden).max().unwrap_or(0);
    let axis_temps: [TempPart; 3] =
        axis_temps
            .try_into()
            .map_err(|_| CompileError::Inconsistent {
                reason: "expected three axis parts".into(),
            })?;
    Ok(CompiledHybrid {
        sensors: p.sensor_names().to_vec(),
        synthesis,
        neg_shift_mm: p.negative_approach_shift_mm(),
        heads,
        units,
        isa: Isa::detect(),
        c_scratch: vec![0.0; max_hidden].into_boxed_slice(),
        axis_temps,
        spindle,
        squareness,
        inputs,
        spindle_lin_mm: [f64::NAN; 3],
        spindle_tilt_rad: [f64::NAN; 2],
        squareness_rad: [f64::NAN; 3],
        constant_mm: [f64::NAN; 3],
        stale: true,
    })
}

/// The chain's signs and arm masks, and the tool.
fn synthesis_of(g: &MachineGeometry) -> Synthesis {
    let mut sign = [0.0; 3];
    let mut arm_mask = [[0.0; 3]; 3];
    for axis in LinearAxis::ALL {
        let k = axis.index();
        sign[k] = g.chain.side(axis).sign();
        for other in LinearAxis::ALL {
            arm_mask[k][other.index()] = if g.chain.arm_includes(axis, other) {
                1.0
            } else {
                0.0
            };
        }
    }
    Synthesis {
        sign,
        arm_mask,
        tool_offset_mm: g.tool_offset_mm,
    }
}

/// The heads of the three axis parts and their blocks of units (layouts in `query`), the
/// synthesis's units and the sides' signs `sign` folded into the outputs; the linear terms and
/// `c₂` start at zero (the readings stage writes them); padded units have zero weights.
fn pack_axes(nets: &[QueryNet], sign: [f64; 3]) -> ([AxisHead; 3], Box<[UnitBlock]>) {
    let mut units: Vec<UnitBlock> = Vec::new();
    let mut heads = [AxisHead::default(); 3];
    for ((head, net), sign) in heads.iter_mut().zip(nets).zip(sign) {
        let h = net.hidden;
        head.hidden = h;
        head.start = units.len();
        head.blocks = h.div_ceil(4);
        head.pos_norm = [0.0, 1.0];
        head.out_scale = std::array::from_fn(|o| sign * if o < 3 { 1e-3 } else { 1e-6 });
        if h == 0 {
            continue;
        }
        head.b2.copy_from_slice(&net.b2);
        for o in 0..N_OUT {
            head.out_std[o] = net.out_std[o] * head.out_scale[o];
            head.out_mean[o] = net.out_mean[o] * head.out_scale[o];
        }
        head.pos_norm = [net.pos_mean, net.pos_std];
        let mut blocks = vec![UnitBlock::default(); head.blocks];
        for j in 0..h {
            let b = &mut blocks[j / 4];
            b.w2[j % 4] = 2.0 * net.w_pos[j] / net.pos_std;
            for o in 0..N_OUT {
                b.v[j % 4][o] = net.w2[o * h + j];
            }
        }
        units.extend_from_slice(&blocks);
    }
    (heads, units.into_boxed_slice())
}

/// Splits a part with `n_pos` (0 or 1) position inputs and `n_t` temperature inputs into its
/// readings-stage coefficients and, when it has a net, the net's query columns (as
/// `part::PartRuntime::new` and `fastnet::SplitNet::new` read a part).
fn split_part(
    part: &LinearPlusNet,
    n_pos: usize,
    n_t: usize,
    n_out: usize,
    name: &'static str,
) -> Result<(PartCoefficients, Option<QueryNet>), CompileError> {
    let lin = &part.linear;
    let n_in = lin.n_in();
    let bilinear = part.bilinear && n_pos > 0;
    let n_base = n_pos + n_t;
    let expected = if bilinear {
        n_base + n_pos * n_t
    } else {
        n_base
    };
    if n_in != expected || lin.n_out() != n_out || lin.slopes().len() != n_in * n_out {
        return Err(CompileError::Inconsistent {
            reason: format!(
                "linear model `{name}` maps {n_in} → {} values; expected {expected} → {n_out}",
                lin.n_out()
            ),
        });
    }
    let mut c = PartCoefficients {
        n_t,
        n_out,
        intercept: lin.intercept().to_vec(),
        ..PartCoefficients::default()
    };
    for row in lin.slopes().chunks_exact(n_in) {
        c.lin_temp.extend_from_slice(&row[n_pos..n_base]);
        if n_pos > 0 {
            c.lin_pos.push(row[0]);
        }
        if bilinear {
            c.lin_bil.extend_from_slice(&row[n_base..n_base + n_t]);
        }
    }
    let net = match &part.net {
        Some(reg) => Some(split_net(reg, n_pos, n_t, n_out, name, &mut c)?),
        None => None,
    };
    Ok((c, net))
}

/// The net's temperature columns into `c`, its query columns returned.
fn split_net(
    reg: &Regressor,
    n_pos: usize,
    n_t: usize,
    n_out: usize,
    name: &'static str,
    c: &mut PartCoefficients,
) -> Result<QueryNet, CompileError> {
    let mlp = reg.mlp();
    let sizes = mlp.sizes();
    let n_in = n_pos + n_t;
    if sizes.len() != 3 || sizes[0] != n_in || sizes[2] != n_out || sizes[1] == 0 {
        return Err(CompileError::Inconsistent {
            reason: format!(
                "network `{name}` has layer sizes {sizes:?}; expected [{n_in}, hidden, {n_out}]"
            ),
        });
    }
    if mlp.activation() != Activation::Tanh {
        return Err(CompileError::ApproximateActivation { net: name });
    }
    let h = sizes[1];
    let (w1, rest) = mlp.weights().split_at(h * n_in);
    let (b1, rest) = rest.split_at(h);
    let (w2, b2) = rest.split_at(n_out * h);
    let (inorm, onorm) = (reg.input_norm(), reg.output_norm());
    c.hidden = h;
    c.b1 = b1.to_vec();
    c.temp_mean = inorm.mean[n_pos..].to_vec();
    c.temp_std = inorm.std[n_pos..].to_vec();
    let mut w_pos = Vec::with_capacity(h);
    for row in w1.chunks_exact(n_in) {
        w_pos.extend_from_slice(&row[..n_pos]);
        c.w_temp.extend_from_slice(&row[n_pos..]);
    }
    Ok(QueryNet {
        hidden: h,
        w_pos,
        w2: w2.to_vec(),
        b2: b2.to_vec(),
        out_std: onorm.std.clone(),
        out_mean: onorm.mean.clone(),
        pos_mean: if n_pos > 0 { inorm.mean[0] } else { 0.0 },
        pos_std: if n_pos > 0 { inorm.std[0] } else { 1.0 },
    })
}
