//! What a caught panic says: the fronts turn a panic into an error instead of an abort, and the
//! readers of third-party formats turn a crate's panic on a damaged file into a reading error.

/// The message a panic's payload carries ("no message" when it is not text).
pub(crate) fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into())
}
