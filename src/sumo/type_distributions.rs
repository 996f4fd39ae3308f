//! The vehicle-type distributions (`<vTypeDistribution>`) of a SUMO configuration's route and
//! additional files, with their member types. SUMO lists a distribution's id among the vehicle
//! types, but a vehicle of it gets the type drawn from it: `--cav-types` naming the
//! distribution would make no CAV at all.

use std::collections::BTreeMap;
use std::path::Path;

use super::scenario_files::named_files;
use super::sumocfg::{SumoConfig, SumoConfigError};
use crate::io::bounded::{read_text, FileKind};

/// One distribution: the file that defines it (as the configuration names it) and its member
/// types, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Distribution {
    /// The file, as the configuration names it.
    pub file: String,
    /// Its member vehicle types.
    pub members: Vec<String>,
}

/// Every `<vTypeDistribution>` of the files the configuration `cfg` names (its network
/// aside), by id.
///
/// # Errors
/// The configuration or a file it names cannot be read or is no XML.
pub fn distributions(cfg: &SumoConfig) -> Result<BTreeMap<String, Distribution>, SumoConfigError> {
    let mut out = BTreeMap::new();
    for (name, path) in named_files(&cfg.path)? {
        if path == cfg.path || path == cfg.net || !path.is_file() {
            continue;
        }
        let text = read_text(&path, FileKind::Network).map_err(|cause| SumoConfigError::Read {
            path: path.clone(),
            cause,
        })?;
        if !text.contains("vTypeDistribution") {
            continue;
        }
        for (id, members) in in_text(&path, &text)? {
            let file = name.clone();
            out.entry(id).or_insert(Distribution { file, members });
        }
    }
    Ok(out)
}

/// The distributions defined in the XML `text` of the file at `path`: their member types are
/// the `<vType>` elements inside, or the ids of their `vTypes` attribute.
fn in_text(path: &Path, text: &str) -> Result<Vec<(String, Vec<String>)>, SumoConfigError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| SumoConfigError::Content {
        path: path.to_path_buf(),
        what: e.to_string(),
    })?;
    let found = doc
        .descendants()
        .filter(|n| n.has_tag_name("vTypeDistribution"))
        .filter_map(|n| {
            let id = n.attribute("id")?.to_string();
            let mut members: Vec<String> = n
                .children()
                .filter(|c| c.has_tag_name("vType"))
                .filter_map(|c| c.attribute("id").map(String::from))
                .collect();
            if let Some(listed) = n.attribute("vTypes") {
                members.extend(listed.split_whitespace().map(String::from));
            }
            Some((id, members))
        })
        .collect();
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn members_inside_and_listed_are_found() {
        let text = r#"<routes>
            <vTypeDistribution id="mix"><vType id="car" probability="0.8"/><vType id="lorry"/>
            </vTypeDistribution><vType id="bus"/><vType id="taxi"/>
            <vTypeDistribution id="listed" vTypes="bus taxi"/></routes>"#;
        let found = in_text(Path::new("r.rou.xml"), text).unwrap();
        assert_eq!(
            found,
            [
                ("mix".to_string(), vec!["car".to_string(), "lorry".into()]),
                ("listed".to_string(), vec!["bus".to_string(), "taxi".into()]),
            ]
        );
    }
}
