//! Voxelizers.
