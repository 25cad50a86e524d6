//! Data handed over in memory (from Python: `arbvis.Volume`, `arbvis.Cloud`), shelved under
//! a name that a scene gives as it gives a file (`volume = { memory = "volume-1" }`,
//! `cloud = { memory = "cloud-1" }`). A shelf holds its items weakly: one lives as long as
//! its owners (the Python object, the scenes it was put in), and a name whose item is
//! gone, or that was given in another process, finds nothing.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, Weak};

/// The items of one kind, by name.
pub struct Shelf<T> {
    kind: &'static str,
    items: Mutex<(u64, BTreeMap<String, Weak<T>>)>,
}

impl<T> Shelf<T> {
    /// An empty shelf whose names are `KIND-N`.
    pub const fn new(kind: &'static str) -> Shelf<T> {
        Shelf {
            kind,
            items: Mutex::new((0, BTreeMap::new())),
        }
    }

    /// Shelve `item`; its name (`KIND-N`, never given twice in this process).
    pub fn register(&self, item: &Arc<T>) -> String {
        let mut guard = self.items.lock().unwrap_or_else(|e| e.into_inner());
        let (last, map) = &mut *guard;
        *last += 1;
        let name = format!("{}-{last}", self.kind);
        // The names of items that are gone leave as new ones come.
        map.retain(|_, v| v.strong_count() > 0);
        map.insert(name.clone(), Arc::downgrade(item));
        name
    }

    /// The item shelved as `name`, while one of its owners holds it.
    pub fn get(&self, name: &str) -> Option<Arc<T>> {
        let guard = self.items.lock().unwrap_or_else(|e| e.into_inner());
        guard.1.get(name).and_then(Weak::upgrade)
    }

    /// A copy of the item shelved as `name`.
    pub fn copy(&self, name: &str) -> Result<T, Missing>
    where
        T: Clone,
    {
        self.get(name)
            .map(|item| (*item).clone())
            .ok_or_else(|| self.missing(name))
    }

    /// The error for `name`, which finds nothing.
    pub fn missing(&self, name: &str) -> Missing {
        Missing {
            kind: self.kind,
            name: name.to_string(),
        }
    }
}

/// A name that finds nothing on its shelf.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("memory = {name:?}: no such {kind} in this process (one handed over from Python lives in the process that made it, while it or a scene holding it is referenced)")]
pub struct Missing {
    /// What the shelf holds (`volume`, `cloud`, `mesh`).
    pub kind: &'static str,
    /// The name.
    pub name: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_item_is_found_while_it_lives_and_names_are_never_reused() {
        static SHELF: Shelf<Vec<u8>> = Shelf::new("thing");
        let a = Arc::new(vec![1u8, 2, 3]);
        let name = SHELF.register(&a);
        let again = SHELF.register(&a);
        assert_ne!(name, again);
        assert_eq!(SHELF.get(&name).as_deref(), Some(&vec![1, 2, 3]));
        drop(a);
        assert!(SHELF.get(&name).is_none());
        let b = Arc::new(vec![4u8]);
        let third = SHELF.register(&b);
        assert!(third != name && third != again && third.starts_with("thing-"));
        let e = SHELF.copy(&name).unwrap_err();
        assert_eq!((e.kind, e.name.as_str()), ("thing", name.as_str()));
        assert!(
            e.to_string().contains("no such thing in this process"),
            "{e}"
        );
    }
}
