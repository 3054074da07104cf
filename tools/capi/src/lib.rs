//! The tagsplat C ABI (skeleton: being written).
