//! Milling dynamics of vmc-twin: regenerative chatter stability of a milling tool tip.
//!
//! Model: the tool-tip modes in x (feed) and y ([`params::TipModes`], several modes per
//! direction, a direction without modes is rigid) are excited by the Altintas–Budak linear
//! cutting force F = a_p·H(φ(t))·(q(t) − q(t − τ)) with the regenerative delay
//! τ = 60/(N n) s (tooth period), H the screened directional matrix of [`forces`] (K_t, K_n in
//! N/m²) and optional process damping −(C a_p / v_c)·D(φ)·q̇. The resulting periodic delay
//! equation is analysed three ways:
//! * [`zoa`] — zero-order analytic solution (Altintas–Budak): H replaced by its mean A₀;
//!   a_lim = 1/(2 Re Λ), Λ eigenvalues of G(iω)A₀; Hopf lobes only;
//! * [`sdm`] (generic) and [`milling`] — first-order semi-discretisation (Insperger–Stépán),
//!   monodromy matrix over one tooth period, stable when its spectral radius is < 1, loss of
//!   stability classified as Hopf (complex multiplier) or flip (−1); [`converged`] chooses the
//!   steps per tooth period for accuracy (the default of [`lobes()`]), [`arnoldi`] gives the
//!   dominant multiplier of large monodromy matrices;
//! * [`time_domain`] — RK4 simulation with a delay buffer (linear or with feed, edge forces
//!   and loss of contact), instability = growth of the once-per-tooth vibration amplitude.
//!
//! [`lobes()`] gives one API for the stability lobes of all three; [`beam`] builds tip modes
//! of an Euler–Bernoulli clamped-free cantilever; [`modal`] the state-space form;
//! [`modal_fit`] fits tip modes to a measured receptance FRF.
//!
//! [`cut`] simulates one cut with the process force (feed, edge forces, loss of contact) from
//! its steady vibration and judges it stable or chattering; [`spectrum`] gives its amplitude
//! spectrum (radix-2 FFT).
//!
//! Helical teeth: the flute is cut into axial disks that lag by the helix (see [`forces`]);
//! SDM and the time domain use them, ZOA's mean directional matrix does not depend on the
//! helix. Assumptions: uniform pitch, linear force law (edge forces only in the time domain's
//! process model), a tool rigid along its axis (every disk sees the tip's displacement),
//! rigid workpiece, constant speed. Units: SI unless the
//! name says `_mm`, `_rpm`, `_deg`. Everything is f64, deterministic and free of I/O.

#![warn(missing_docs)]

pub mod arnoldi;
pub mod beam;
pub mod control;
pub mod converged;
pub mod cut;
pub mod forces;
pub mod lobes;
pub mod milling;
pub mod modal;
pub mod modal_fit;
pub mod params;
pub mod sdm;
pub mod spectrum;
pub mod time_domain;
pub mod zoa;

pub use converged::{Resolution, StepRule};
pub use cut::{simulate_cut, CutOptions, CutSimulation, Verdict};
pub use lobes::{lobes, sdm_lowest_critical_depth, LobePoint, Method};
pub use params::{Cut, DynamicsError, Milling, Mode, TipModes, Tool};
pub use sdm::BoundaryKind;
