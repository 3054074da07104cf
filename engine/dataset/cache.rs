//! A bounded least-recently-used cache of decoded images, so a long multi-view sequence never
//! needs all its images in memory at once.

use crate::io::image::Image;
use std::collections::{HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Holds decoded images up to `budget` bytes of pixel data (at least the most recent one).
#[derive(Debug)]
pub struct ImageCache {
    budget: usize,
    inner: Mutex<Entries>,
}

#[derive(Debug, Default)]
struct Entries {
    images: HashMap<PathBuf, Arc<Image>>,
    order: VecDeque<PathBuf>, // least recent first
    bytes: usize,
}

fn size_of(image: &Image) -> usize {
    image.data.len() * std::mem::size_of::<f32>()
}

impl ImageCache {
    /// An empty cache holding up to `budget` bytes of pixel data (f32 samples).
    pub fn new(budget: usize) -> Self {
        Self { budget, inner: Mutex::new(Entries::default()) }
    }

    /// The cached image at `path`, or `load(path)` inserted (evicting the least recently used
    /// images beyond the budget).
    pub fn get_or_load<E>(
        &self,
        path: &Path,
        load: impl FnOnce(&Path) -> Result<Image, E>,
    ) -> Result<Arc<Image>, E> {
        {
            let mut e = self.inner.lock().unwrap_or_else(|p| p.into_inner());
            if let Some(image) = e.images.get(path).cloned() {
                e.order.retain(|p| p != path);
                e.order.push_back(path.to_owned());
                return Ok(image);
            }
        }
        // Decoded outside the lock, so other threads keep reading the cache meanwhile.
        let image = Arc::new(load(path)?);
        let mut e = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        if e.images.insert(path.to_owned(), image.clone()).is_none() {
            e.bytes += size_of(&image);
            e.order.push_back(path.to_owned());
        }
        while e.bytes > self.budget && e.order.len() > 1 {
            if let Some(old) = e.order.pop_front() {
                if let Some(img) = e.images.remove(&old) {
                    e.bytes -= size_of(&img);
                }
            }
        }
        Ok(image)
    }

    /// Bytes of pixel data held now.
    pub fn bytes(&self) -> usize {
        self.inner.lock().unwrap_or_else(|p| p.into_inner()).bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evicts_least_recent_beyond_the_budget() {
        let img =
            |_: &Path| Ok::<_, ()>(Image { width: 2, height: 2, channels: 1, data: vec![0.0; 4] }); // 16 bytes
        let cache = ImageCache::new(40);
        let loads = std::cell::Cell::new(0);
        let counted = |p: &Path| {
            loads.set(loads.get() + 1);
            img(p)
        };
        for name in ["a", "b", "a", "c", "a", "b"] {
            cache.get_or_load(Path::new(name), counted).unwrap();
        }
        // a, b loaded; a hit; c loaded and b (least recent) evicted; a hit; b reloaded.
        assert_eq!(loads.get(), 4);
        assert!(cache.bytes() <= 40);
    }
}
