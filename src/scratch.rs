//! Thread-local scratch buffers: work arrays for evaluations that take `&self` (a system's
//! forces, AD derivatives) and must not allocate inside the step loop. A buffer grows on a
//! thread's first call of a size and is reused after.

use std::cell::RefCell;
use std::thread::LocalKey;

/// Run `body` with a scratch slice of length `len` from the thread-local buffer `key`: its
/// contents are unspecified (`fill` where the buffer grew, a previous call's values elsewhere),
/// so `body` writes every entry it reads. A nested call, which cannot borrow the buffer, gets
/// a fresh vector instead of panicking.
pub(crate) fn with_scratch<S: Copy, R>(
    key: &'static LocalKey<RefCell<Vec<S>>>,
    len: usize,
    fill: S,
    body: impl FnOnce(&mut [S]) -> R,
) -> R {
    key.with(|cell| match cell.try_borrow_mut() {
        Ok(mut buf) => {
            if buf.len() < len {
                buf.resize(len, fill);
            }
            body(&mut buf[..len])
        }
        Err(_) => body(&mut vec![fill; len]),
    })
}
