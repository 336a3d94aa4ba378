//! Loaders tested together on generated models.
