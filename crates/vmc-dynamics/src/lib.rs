//! Milling dynamics of vmc-twin: regenerative chatter stability of a milling tool tip.
//!
//! Model: the tool-tip modes in x (feed) and y ([`params::TipModes`]) are excited by the
//! Altintas–Budak linear cutting force F = a_p·H(φ(t))·(q(t) − q(t − τ)) with the
//! regenerative delay τ = 60/(N n) s (tooth period, uniform pitch, straight teeth) and the
//! screen function of the engagement window ([`forces`]). Stability of this periodic delay
//! equation is computed three ways:
//! * [`zoa`] — zero-order analytic solution (Altintas–Budak): H replaced by its mean;
//! * [`sdm`] / [`milling`] — first-order semi-discretisation (Insperger–Stépán);
//! * [`time_domain`] — direct simulation with a delay buffer.
//!
//! [`lobes`] gives one API for the stability lobes of all three. [`beam`] builds tip modes of
//! an Euler–Bernoulli cantilever. Units: SI unless the name says `_mm`, `_rpm`, `_deg`.
//! Everything is f64, deterministic and free of I/O.

pub mod beam;
pub mod forces;
pub mod lobes;
pub mod milling;
pub mod modal;
pub mod params;
pub mod sdm;
pub mod time_domain;
pub mod zoa;


pub use lobes::{lobes, LobePoint, Method};
pub use params::{Cut, DynamicsError, Milling, Mode, TipModes, Tool};
pub use sdm::BoundaryKind;
