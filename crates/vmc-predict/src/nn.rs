//! Multilayer perceptrons and their training.
