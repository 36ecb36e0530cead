//! Loading real and broken scene files.
