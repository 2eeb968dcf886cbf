//! mpm (placeholder)
