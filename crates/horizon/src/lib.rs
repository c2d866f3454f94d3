//! Sector horizons (placeholder until the sweep lands).
