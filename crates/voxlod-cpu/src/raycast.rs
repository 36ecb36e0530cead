//! BVH ray casting.
