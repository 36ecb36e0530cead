//! Evaluation: metrics and reports.
