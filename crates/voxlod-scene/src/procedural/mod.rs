//! Deterministic procedural scenes.
