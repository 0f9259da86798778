//! The real scenes of `shared/scenes` (its README describes them) and where to find them:
//! names and triangle counts -> paths.
//!
//! The meshes live beside the repository (`../shared/scenes` from its root) and are never
//! copied into it. [`scenes_dir`] looks in `SCION_SCENES` first, then for `shared/scenes` in
//! every ancestor of the current directory and of this crate's source folder.

use std::path::{Path, PathBuf};

/// One real scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneInfo {
    /// File stem (`NAME.obj`).
    pub name: &'static str,
    /// Triangles in the file.
    pub triangles: usize,
}

/// The real scenes, smallest first, with their triangle counts (shared/scenes/README.md).
pub const REAL_SCENES: &[SceneInfo] = &[
    SceneInfo {
        name: "teapot",
        triangles: 992,
    },
    SceneInfo {
        name: "pine",
        triangles: 1_650,
    },
    SceneInfo {
        name: "suzanne",
        triangles: 15_488,
    },
    SceneInfo {
        name: "balloon",
        triangles: 35_698,
    },
    SceneInfo {
        name: "fzk_haus",
        triangles: 35_906,
    },
    SceneInfo {
        name: "sponza_dabrovic",
        triangles: 66_454,
    },
    SceneInfo {
        name: "bunny",
        triangles: 69_630,
    },
    SceneInfo {
        name: "engine",
        triangles: 110_336,
    },
    SceneInfo {
        name: "cruiser_cg57",
        triangles: 180_063,
    },
    SceneInfo {
        name: "dragon",
        triangles: 871_306,
    },
];

/// The scene called `name`, if listed.
pub fn find(name: &str) -> Option<&'static SceneInfo> {
    REAL_SCENES.iter().find(|s| s.name == name)
}

fn looks_like_scenes(dir: &Path) -> bool {
    dir.join("teapot.obj").is_file()
}

/// The folder of the real scenes, or `None` when it cannot be found.
pub fn scenes_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("SCION_SCENES") {
        let dir = PathBuf::from(dir);
        return looks_like_scenes(&dir).then_some(dir);
    }
    let starts = [
        std::env::current_dir().ok(),
        Some(PathBuf::from(env!("CARGO_MANIFEST_DIR"))),
    ];
    starts
        .into_iter()
        .flatten()
        .flat_map(|start| {
            start
                .ancestors()
                .map(|a| a.join("shared").join("scenes"))
                .collect::<Vec<_>>()
        })
        .find(|d| looks_like_scenes(d))
}

impl SceneInfo {
    /// The scene's path inside `dir`.
    pub fn path(&self, dir: &Path) -> PathBuf {
        dir.join(format!("{}.obj", self.name))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listed_smallest_first_and_findable() {
        assert!(REAL_SCENES
            .windows(2)
            .all(|w| w[0].triangles < w[1].triangles));
        assert_eq!(find("dragon").unwrap().triangles, 871_306);
        assert!(find("lucy").is_none());
        assert_eq!(
            find("pine").unwrap().path(Path::new("/s")),
            PathBuf::from("/s/pine.obj")
        );
    }
}
