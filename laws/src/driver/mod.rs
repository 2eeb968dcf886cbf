//! Material-point test driver.
