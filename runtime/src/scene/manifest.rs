//! The real scenes of the repository's `scenes/` folder (its README describes them, with their
//! sources and licences) and where to find them: names and triangle counts -> paths.
//!
//! The repository carries them gzip-compressed (`scenes/NAME.obj.gz`; [`super::load_obj`]
//! reads them as they are). [`scenes_dir`] looks in `SCION_SCENES` first (a folder of
//! `NAME.obj` or `NAME.obj.gz` files), then for `scenes/` in every ancestor of the current
//! directory and of this crate's source folder. [`resolve`] turns a command line's `--scene`
//! (a path, or a real scene's name) into a path.

use std::path::{Path, PathBuf};

/// One real scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneInfo {
    /// File stem (`NAME.obj`).
    pub name: &'static str,
    /// Triangles in the file.
    pub triangles: usize,
}

/// The real scenes, smallest first, with their triangle counts (scenes/README.md).
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
    REAL_SCENES[0].file_in(dir).is_some()
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
                .map(|a| a.join("scenes"))
                .collect::<Vec<_>>()
        })
        .find(|d| looks_like_scenes(d))
}

impl SceneInfo {
    /// The scene's file inside `dir`: `NAME.obj` when there is one (an unpacked copy), else
    /// `NAME.obj.gz`; `None` when neither exists.
    pub fn file_in(&self, dir: &Path) -> Option<PathBuf> {
        [
            dir.join(format!("{}.obj", self.name)),
            dir.join(format!("{}.obj.gz", self.name)),
        ]
        .into_iter()
        .find(|p| p.is_file())
    }

    /// The scene's path inside `dir` ([`Self::file_in`], or `NAME.obj.gz` when neither file
    /// exists, so that loading it names the missing file).
    pub fn path(&self, dir: &Path) -> PathBuf {
        self.file_in(dir)
            .unwrap_or_else(|| dir.join(format!("{}.obj.gz", self.name)))
    }
}

/// What a `--scene` argument names: an existing file, or anything that looks like a path (a
/// folder separator or an extension; loading it names what is wrong), as given; else a real
/// scene's name (`bunny`) as its file in [`scenes_dir`]. `Err` says why a bare name is neither.
pub fn resolve(arg: &Path) -> Result<PathBuf, String> {
    if arg.exists() || arg.components().count() > 1 || arg.extension().is_some() {
        return Ok(arg.to_path_buf());
    }
    let names = || {
        REAL_SCENES
            .iter()
            .map(|s| s.name)
            .collect::<Vec<_>>()
            .join(", ")
    };
    match arg.to_str().and_then(find) {
        Some(info) => match scenes_dir() {
            Some(dir) => Ok(info.path(&dir)),
            None => Err(format!(
                "`{}` is a library scene, but its folder was not found (the repository's \
                 scenes/, or SCION_SCENES)",
                info.name
            )),
        },
        None => Err(format!(
            "no such file, and not a library scene ({})",
            names()
        )),
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
            find("pine").unwrap().path(Path::new("/nonexistent")),
            PathBuf::from("/nonexistent/pine.obj.gz")
        );
    }
}

#[cfg(test)]
mod repo_tests {
    use super::*;

    /// The repository carries every listed scene (what makes a clone self-contained).
    #[test]
    fn the_repository_has_every_scene() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        for s in REAL_SCENES {
            assert!(
                dir.join(format!("{}.obj.gz", s.name)).is_file(),
                "scenes/{}.obj.gz is missing",
                s.name
            );
        }
        assert!(resolve(Path::new("teapot")).is_ok());
        let e = resolve(Path::new("no-such-scene")).unwrap_err();
        assert!(e.contains("teapot, pine"), "{e}");
    }
}
