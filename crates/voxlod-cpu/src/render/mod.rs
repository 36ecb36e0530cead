//! Renderers: the ground truth on the mesh, and voxel renderers.
