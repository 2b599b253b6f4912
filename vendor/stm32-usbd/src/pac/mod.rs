#[allow(unused, non_camel_case_types)]
pub mod usb;

#[allow(dead_code)]
mod generic;
