//! TODO
/// Blends between gaits (to be implemented).
pub struct GaitSelector;
