//! Colliders and collision response (to be written).
