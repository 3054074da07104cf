//! The tagsplat Python package (skeleton: being written).
