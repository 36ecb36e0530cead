//! binvox occupancy export and import.
