//! The machine-file fragment written by `identify-thermal`: the identified network in the
//! `[thermal]` vocabulary of a machine file, and the drift channels as thermal error terms.
//!
//! ```toml
//! [thermal]
//! ambient = { kind = "constant", temp_degc = 26.19 }
//! nodes = [
//!   { name = "spindle_fit_0", capacity_j_per_k = 20000.0, ha_w_per_k = 3.1, ha_gain_per_krpm = 0.2 },
//! ]
//! links = [
//! ]
//! sources = [
//!   { kind = "spindle_bearing", node = "spindle_fit_0", torque_n_mm = 80.1, torque_per_krpm_n_mm = 9.3 },
//! ]
//!
//! [identified_drift.ch1_um]
//! ref_temp_degc = 26.19
//! offset_um = 0.4
//! thermal = [
//!   { shape = "constant", gain_um_per_k = 1.25, weights = { spindle_fit_0 = 1.0 } },
//! ]
//! ```
//!
//! Drift of a channel = `offset + Σ gain · Σ weight·(T_node − ref_temp_degc)`, the form of a
//! machine file's `[errors.spindle.*]` thermal terms (shape `constant`). One entry per line, so
//! that merging into a machine file is pasting lines into its `nodes`, `links` and `sources`
//! lists (the fragment's nodes form a chain of their own, linked to nothing else). The
//! `[identified_drift]` table is not part of a machine file: its terms go under the
//! `[errors.spindle.*]` error each probe channel measures.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Deserialize;

use super::{Columns, IdentifyThermalConfig};
use crate::predict::rc_identify::{RcFit, BEARING_W_PER_KRPM_N_MM};
use crate::predict::thermal_fit::Table;
use vmc_machine::errors::spec::ThermalTermSpec;
use vmc_machine::thermal::ThermalSpec;

/// Prefix of the fragment's node names (`spindle_fit_0`, `spindle_fit_1`, …).
pub const NODE_PREFIX: &str = "spindle_fit_";

/// Name of node `i` in the fragment.
#[must_use]
pub fn node_name(i: usize) -> String {
    format!("{NODE_PREFIX}{i}")
}

/// What the fragment's header says it was fitted on.
pub struct Meta {
    /// File name.
    pub source: String,
    /// Rows fitted.
    pub rows: usize,
    /// First and last time, s.
    pub span_s: [f64; 2],
    /// Speed column.
    pub rpm: String,
    /// Drift columns.
    pub drifts: Vec<String>,
    /// Node temperature columns.
    pub node_temps: Vec<String>,
    /// Ambient column.
    pub ambient: Option<String>,
    /// Reference (and ambient) temperature of the fragment, °C.
    pub ref_temp_degc: f64,
    /// Median time step of the file, s.
    pub step_s: f64,
}

impl Meta {
    /// The header facts of a fit of `cfg` on `table`. The reference temperature: the first
    /// ambient reading, else the first reading of node 0's temperature, else 20 °C.
    #[must_use]
    pub(crate) fn new(cfg: &IdentifyThermalConfig, table: &Table, cols: &Columns) -> Self {
        let t = &table.time_s;
        let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(f64::total_cmp);
        let first = |c: Option<&[f64]>| c.and_then(|c| c.first().copied());
        Self {
            source: cfg.data.display().to_string(),
            rows: t.len(),
            span_s: [
                t.first().copied().unwrap_or(0.0),
                t.last().copied().unwrap_or(0.0),
            ],
            rpm: cfg.rpm.clone(),
            drifts: cfg.drifts.clone(),
            node_temps: cfg.node_temps.clone(),
            ambient: cfg.ambient.clone(),
            ref_temp_degc: first(cols.ambient)
                .or_else(|| first(cols.node_temps.first().copied().flatten()))
                .unwrap_or(20.0),
            step_s: steps.get(steps.len() / 2).copied().unwrap_or(1.0),
        }
    }
}

/// A number as TOML writes it (always with a decimal point or exponent).
fn num(v: f64) -> String {
    let s = format!("{v:?}");
    if s.contains(['.', 'e', 'E']) || !v.is_finite() {
        s
    } else {
        format!("{s}.0")
    }
}

/// The unit suffix of a drift column (`um` for `ch1_um`), `um` if none is known.
fn unit(name: &str) -> &'static str {
    if name.ends_with("_urad") {
        "urad"
    } else {
        "um"
    }
}

/// The fragment's text for a speed-only `fit` (see the module doc).
#[must_use]
pub fn write(meta: &Meta, fit: &RcFit) -> String {
    let net = &fit.network;
    let n = net.nodes();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Spindle thermal network identified by `vmc-twin identify-thermal` from {}:\n\
         # {} rows, {}–{} s; heat input from the speed column \"{}\"; drift channels {}; node \
         temperatures fitted: {}; ambient: {}.\n\
         # {} node(s) in a chain, heat into node 0; drift from the speed profile alone. Node 0's \
         capacity was fixed\n\
         # (the data fix only ratios of heat, conductance and capacity).{}\n\
         # Merge into a machine file: paste the lines of `nodes`, `links` and `sources` into the \
         lists of its [thermal]\n\
         # table; move each [identified_drift.*] `thermal` list to the [errors.spindle.*] error \
         its probe measures.\n\
         # The fit integrated the network on the file's own steps (median {} s); a machine's \
         step_s integrates it finer.",
        meta.source,
        meta.rows,
        meta.span_s[0],
        meta.span_s[1],
        meta.rpm,
        meta.drifts.join(", "),
        if meta.node_temps.is_empty() {
            "none (the temperature scale is not identified: only heat × gain is)".to_string()
        } else {
            meta.node_temps
                .iter()
                .enumerate()
                .map(|(i, c)| format!("{} ← {c}", node_name(i)))
                .collect::<Vec<_>>()
                .join(", ")
        },
        meta.ambient.as_deref().unwrap_or("constant"),
        n,
        if fit.at_bounds.is_empty() {
            String::new()
        } else {
            format!(
                "\n# Parameters held at a bound of the fit: {}.",
                fit.at_bounds.join(", ")
            )
        },
        meta.step_s,
    );
    let _ = writeln!(s, "[thermal]");
    let _ = writeln!(
        s,
        "ambient = {{ kind = \"constant\", temp_degc = {} }}",
        num(meta.ref_temp_degc)
    );
    let _ = writeln!(s, "nodes = [");
    for i in 0..n {
        let gain = if i == 0 && net.ha_gain_per_krpm > 0.0 {
            format!(", ha_gain_per_krpm = {}", num(net.ha_gain_per_krpm))
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  {{ name = \"{}\", capacity_j_per_k = {}, ha_w_per_k = {}{gain} }},",
            node_name(i),
            num(net.capacity_j_per_k[i]),
            num(net.ambient_w_per_k[i])
        );
    }
    let _ = writeln!(s, "]\nlinks = [");
    for (i, g) in net.link_w_per_k.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {{ a = \"{}\", b = \"{}\", conductance_w_per_k = {} }},",
            node_name(i),
            node_name(i + 1),
            num(*g)
        );
    }
    let _ = writeln!(s, "]\nsources = [");
    let _ = writeln!(
        s,
        "  {{ kind = \"spindle_bearing\", node = \"{}\", torque_n_mm = {}, torque_per_krpm_n_mm = {} }},",
        node_name(0),
        num(net.heat_w_per_krpm / BEARING_W_PER_KRPM_N_MM),
        num(net.heat_w_per_krpm2 / BEARING_W_PER_KRPM_N_MM)
    );
    let _ = writeln!(s, "]");
    for (k, g) in fit.gains.iter().enumerate() {
        let name = meta.drifts.get(k).cloned().unwrap_or(format!("ch{k}"));
        let u = unit(&name);
        let _ = writeln!(s, "\n[identified_drift.{name}]");
        let _ = writeln!(s, "ref_temp_degc = {}", num(meta.ref_temp_degc));
        let _ = writeln!(s, "offset_{u} = {}", num(g[0]));
        if fit.with_ambient {
            let _ = writeln!(
                s,
                "# per K of the ambient's rise since the first row (not a twin error term)\n\
                 ambient_gain_{u}_per_k = {}",
                num(g[1 + n])
            );
        }
        let _ = writeln!(s, "thermal = [");
        for i in 0..n {
            let _ = writeln!(
                s,
                "  {{ shape = \"constant\", gain_{u}_per_k = {}, weights = {{ {} = 1.0 }} }},",
                num(g[1 + i]),
                node_name(i)
            );
        }
        let _ = writeln!(s, "]");
    }
    s
}

/// A drift channel of the fragment.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelDrift {
    /// Reference temperature of the terms, °C.
    pub ref_temp_degc: f64,
    /// Offset (µm, or µrad for `offset_urad`).
    #[serde(rename = "offset_um", alias = "offset_urad")]
    pub offset: f64,
    /// Gain per K of the ambient's rise, if the fit had an ambient column.
    #[serde(
        default,
        rename = "ambient_gain_um_per_k",
        alias = "ambient_gain_urad_per_k"
    )]
    pub ambient_gain_per_k: f64,
    /// The terms, as a machine file's `[errors.spindle.*]` ones.
    pub thermal: Vec<ThermalTermSpec>,
}

impl ChannelDrift {
    /// The drift for node temperatures `temp_degc(name)` (°C), without the ambient term.
    pub fn drift(&self, temp_degc: &dyn Fn(&str) -> Option<f64>) -> Option<f64> {
        let mut d = self.offset;
        for term in &self.thermal {
            let mut dt = 0.0;
            for (node, w) in &term.weights {
                dt += w * (temp_degc(node)? - self.ref_temp_degc);
            }
            d += term.gain() * dt;
        }
        Some(d)
    }
}

/// The fragment read back: the `[thermal]` table and the drift channels.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fragment {
    /// The network, in a machine file's vocabulary.
    pub thermal: ThermalSpec,
    /// The drift channels, by column name.
    pub identified_drift: BTreeMap<String, ChannelDrift>,
}

impl Fragment {
    /// Parses a fragment's text.
    ///
    /// # Errors
    /// Not TOML, or not of the fragment's form.
    pub fn parse(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }
}
