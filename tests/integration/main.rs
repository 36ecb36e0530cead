//! End-to-end and cross-crate tests of voxlod, in one test binary (one link on 2-core CI).

mod cli;
mod cone;
mod experiment;
mod scene_files;
mod volume;
