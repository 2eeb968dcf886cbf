//! coupling (placeholder)
