//! placeholder
#[derive(Debug)]
pub enum BatchError {}
#[derive(Clone, Copy, Debug)]
pub enum Method {
    Sptd,
    Ltc,
    Reference,
}
pub fn run_batch(
    _m: Method,
    _i: impl std::io::BufRead,
    _o: impl std::io::Write,
) -> Result<(), BatchError> {
    Ok(())
}
