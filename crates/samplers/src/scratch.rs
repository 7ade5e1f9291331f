//! Per-thread scratch buffers, so that no shading point allocates on the heap: a buffer is
//! taken from its thread's pool, cleared, used for one shading point and handed back when
//! dropped. Contents never carry over (each `take` resets), so results do not depend on which
//! thread ran which pixel.
use std::ops::{Deref, DerefMut};

/// A buffer type with one pool per thread.
pub trait Scratch: Default + Sized + 'static {
    /// Runs `f` on this thread's pool.
    fn with_pool<R>(f: impl FnOnce(&mut Vec<Self>) -> R) -> R;
    /// Forgets the previous user's contents (keeping the capacity).
    fn reset(&mut self);
}

/// A scratch buffer on loan from its thread's pool.
pub struct Pooled<T: Scratch>(Option<T>);

impl<T: Scratch> Pooled<T> {
    pub fn take() -> Self {
        let mut t = T::with_pool(|p| p.pop()).unwrap_or_default();
        t.reset();
        Pooled(Some(t))
    }
}

impl<T: Scratch> Deref for Pooled<T> {
    type Target = T;
    #[inline]
    fn deref(&self) -> &T {
        self.0.as_ref().expect("scratch on loan")
    }
}

impl<T: Scratch> DerefMut for Pooled<T> {
    #[inline]
    fn deref_mut(&mut self) -> &mut T {
        self.0.as_mut().expect("scratch on loan")
    }
}

impl<T: Scratch> Drop for Pooled<T> {
    fn drop(&mut self) {
        if let Some(t) = self.0.take() {
            // A pool holds at most a few buffers (one per live shading point of the thread).
            T::with_pool(|p| {
                if p.len() < 8 {
                    p.push(t)
                }
            });
        }
    }
}

/// Declares `Scratch` for a type with a thread-local pool.
#[doc(hidden)]
#[macro_export]
macro_rules! scratch_pool {
    ($t:ty, $reset:expr) => {
        impl $crate::scratch::Scratch for $t {
            fn with_pool<R>(f: impl FnOnce(&mut Vec<Self>) -> R) -> R {
                thread_local! {
                    static POOL: std::cell::RefCell<Vec<$t>> = const { std::cell::RefCell::new(Vec::new()) };
                }
                POOL.with(|p| f(&mut p.borrow_mut()))
            }
            fn reset(&mut self) {
                let r: fn(&mut $t) = $reset;
                r(self)
            }
        }
    };
}
