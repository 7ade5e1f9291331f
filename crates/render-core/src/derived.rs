//! What strategies derive from a scene and may keep for its next renders (a light tree over
//! its lights, say): opaque to render-core, each item found again by the code that made it. A
//! program that renders one scene many times (the Python package, a notebook) builds such
//! things once; a single render keeps one shared copy, not two.
use std::any::Any;
use std::sync::{Arc, Mutex};

/// Items kept per scene; the oldest is dropped to make room.
const KEEP: usize = 8;

/// A scene's kept items.
#[derive(Default)]
pub struct Derived {
    items: Mutex<Vec<Arc<dyn Any + Send + Sync>>>,
}

impl Derived {
    /// The kept item of type `T` for which `same` holds, else `make`'s, then kept. `make` must
    /// be a pure function of what `same` compares, so that an item found again is the one
    /// `make` would build now.
    pub fn get_or_make<T: Any + Send + Sync, E>(
        &self,
        same: impl Fn(&T) -> bool,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        let mut items = self.items.lock().unwrap_or_else(|e| e.into_inner());
        let found = items
            .iter()
            .filter_map(|item| item.clone().downcast::<T>().ok())
            .find(|t| same(t));
        if let Some(t) = found {
            return Ok(t);
        }
        let t = Arc::new(make()?);
        if items.len() == KEEP {
            items.remove(0);
        }
        items.push(t.clone());
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same key finds the kept item (no second `make`), another key or another type makes
    /// a new one, a failed `make` keeps nothing, and the oldest goes past [`KEEP`].
    #[test]
    fn items_are_found_again_by_their_key() {
        let d = Derived::default();
        let make = |k: u32| move || Ok::<_, ()>((k, vec![k; 3]));
        let a = d
            .get_or_make(|t: &(u32, Vec<u32>)| t.0 == 1, make(1))
            .unwrap();
        let again = d
            .get_or_make(
                |t: &(u32, Vec<u32>)| t.0 == 1,
                || -> Result<_, ()> { panic!("made twice") },
            )
            .unwrap();
        assert!(Arc::ptr_eq(&a, &again));
        let b = d
            .get_or_make(|t: &(u32, Vec<u32>)| t.0 == 2, make(2))
            .unwrap();
        assert!(!Arc::ptr_eq(&a, &b));
        let other_type = d.get_or_make(|_: &String| true, || Ok::<_, ()>("x".to_string()));
        assert_eq!(*other_type.unwrap(), "x");
        assert!(d.get_or_make(|_: &u8| true, || Err::<u8, _>("no")).is_err());
        assert_eq!(*d.get_or_make(|_: &u8| true, || Ok::<_, ()>(7)).unwrap(), 7);
        for k in 10..10 + KEEP as u32 {
            d.get_or_make(|t: &(u32, Vec<u32>)| t.0 == k, make(k))
                .unwrap();
        }
        let a2 = d
            .get_or_make(|t: &(u32, Vec<u32>)| t.0 == 1, make(1))
            .unwrap();
        assert!(!Arc::ptr_eq(&a, &a2), "the oldest was dropped");
    }
}
