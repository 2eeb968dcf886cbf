//! fem (placeholder)
