//! The link checker: every relative link of a set of documents names an existing file, and
//! every `#anchor` a heading of the file it names. Documents come from memory first, so the
//! checker can be tested on planted mistakes, then from the repository.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::has_ext;
use super::markdown::{anchors, links, normalize};

/// Where the link checker looks for what a link names: the documents in memory first, then
/// (for the real tree) the file system under `root`.
pub struct Tree<'a> {
    pub docs: &'a BTreeMap<PathBuf, String>,
    pub root: Option<&'a Path>,
}

impl Tree<'_> {
    fn exists(&self, p: &Path) -> bool {
        self.docs.contains_key(p) || self.root.is_some_and(|r| r.join(p).exists())
    }

    fn text(&self, p: &Path) -> Option<String> {
        match self.docs.get(p) {
            Some(t) => Some(t.clone()),
            None => std::fs::read_to_string(self.root?.join(p)).ok(),
        }
    }
}

/// Every broken relative link of every document: a missing file, or an `#anchor` that no
/// heading of the named Markdown file (or of the same file) has. One line per problem.
pub fn check_links(tree: &Tree) -> Vec<String> {
    let mut problems = Vec::new();
    for (file, text) in tree.docs {
        for (line, target) in links(text) {
            if let Some(p) = broken(tree, file, &target) {
                problems.push(format!("{}:{line}: ({target}) {p}", file.display()));
            }
        }
    }
    problems
}

fn broken(tree: &Tree, file: &Path, target: &str) -> Option<String> {
    let (path, anchor) = target.split_once('#').unwrap_or((target, ""));
    let named = if path.is_empty() {
        file.to_path_buf()
    } else {
        normalize(&file.parent().unwrap_or(Path::new("")).join(path))
    };
    if !tree.exists(&named) {
        return Some(format!("no file {}", named.display()));
    }
    if anchor.is_empty() || !has_ext(&named, "md") {
        return None;
    }
    let text = tree.text(&named)?;
    (!anchors(&text).contains(anchor))
        .then(|| format!("no heading with anchor #{anchor} in {}", named.display()))
}
