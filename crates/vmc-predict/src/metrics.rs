//! Accuracy metrics (DESIGN §9).
