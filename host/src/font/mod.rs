//! Stroke fonts: Hershey for Latin script, hanzi-writer medians for Chinese.
//! Both return strokes in units of the character box so layout can mix them.

pub mod hanzi;
pub mod hershey;
