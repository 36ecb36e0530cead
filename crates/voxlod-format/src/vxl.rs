//! The `.vxl` container (versioned header, grid spec, brick table, payload, checksum).
