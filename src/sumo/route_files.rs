//! What bkpbs reads of a SUMO configuration's route and additional files before SUMO starts:
//! the vehicle-type distributions (`<vTypeDistribution>`) with their member types — SUMO lists
//! a distribution's id among the vehicle types, but a vehicle of it gets the type drawn from
//! it, so `--cav-types` naming the distribution would make no CAV at all — and the demand's
//! size, bounded: a `<flow number="1e9">` once grew SUMO to 3.85 GB before it aborted.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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

/// The most vehicles a scenario's routes may define: far beyond any study here (A10KW's whole
/// game has 6889), far below what fills memory.
pub const MAX_VEHICLES: f64 = 10_000_000.0;

/// The files the configuration `cfg` names (itself and its network aside) whose text holds
/// `needle`, each with the name the configuration gives it, its path and its text.
fn texts_with(
    cfg: &SumoConfig,
    needle: &str,
) -> Result<Vec<(String, PathBuf, String)>, SumoConfigError> {
    let mut out = Vec::new();
    for (name, path) in named_files(&cfg.path)? {
        if path == cfg.path || path == cfg.net || !path.is_file() {
            continue;
        }
        let text = read_text(&path, FileKind::Network).map_err(|cause| SumoConfigError::Read {
            path: path.clone(),
            cause,
        })?;
        if text.contains(needle) {
            out.push((name, path, text));
        }
    }
    Ok(out)
}

/// Every `<vTypeDistribution>` of the files the configuration `cfg` names (its network
/// aside), by id.
///
/// # Errors
/// The configuration or a file it names cannot be read or is no XML.
pub fn distributions(cfg: &SumoConfig) -> Result<BTreeMap<String, Distribution>, SumoConfigError> {
    let mut out = BTreeMap::new();
    for (name, path, text) in texts_with(cfg, "vTypeDistribution")? {
        for (id, members) in in_text(&path, &text)? {
            let file = name.clone();
            out.entry(id).or_insert(Distribution { file, members });
        }
    }
    Ok(out)
}

/// Refuses a demand of more than [`MAX_VEHICLES`] vehicles: each `<flow>` counted by its
/// `number`, or over its `begin`–`end` (cut at the configuration's end) by its rate
/// (`vehsPerHour`, `perHour`, `period`, `probability` per second), before SUMO starts.
///
/// # Errors
/// The largest flow, named with its file, when the demand is beyond the bound; a file that
/// cannot be read or is no XML.
pub fn check_demand(cfg: &SumoConfig) -> Result<(), SumoConfigError> {
    let mut total = 0.0;
    let mut largest: Option<(f64, String, String)> = None;
    for (name, path, text) in texts_with(cfg, "<flow")? {
        for (id, n) in flows(&path, &text, cfg)? {
            total += n;
            if largest.as_ref().is_none_or(|(m, _, _)| n > *m) {
                largest = Some((n, id, name.clone()));
            }
        }
    }
    match largest {
        Some((n, id, file)) if total > MAX_VEHICLES => Err(SumoConfigError::Content {
            path: cfg.path.clone(),
            what: format!(
                "its flows define about {total:.3e} vehicles (flow '{id}' of {file} alone \
                 {n:.3e}), more than bkpbs runs ({MAX_VEHICLES:e}): SUMO would fill memory"
            ),
        }),
        _ => Ok(()),
    }
}

/// Each `<flow>` of the XML `text` (of the file at `path`) with the vehicles it defines.
fn flows(path: &Path, text: &str, cfg: &SumoConfig) -> Result<Vec<(String, f64)>, SumoConfigError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| SumoConfigError::Content {
        path: path.to_path_buf(),
        what: e.to_string(),
    })?;
    let num = |n: roxmltree::Node, k: &str| n.attribute(k).and_then(|v| v.parse::<f64>().ok());
    Ok(doc
        .descendants()
        .filter(|n| n.has_tag_name("flow"))
        .map(|n| {
            let begin = num(n, "begin").unwrap_or(0.0);
            // SUMO's default end of a flow is a day; no further than the configuration runs.
            let end = num(n, "end")
                .unwrap_or(86_400.0)
                .min(cfg.end.unwrap_or(f64::INFINITY));
            let span = (end - begin).max(0.0);
            let rate = ["vehsPerHour", "perHour"]
                .iter()
                .find_map(|k| num(n, k).map(|v| v / 3600.0))
                .or_else(|| num(n, "period").map(|p| 1.0 / p.max(1e-9)))
                .or_else(|| num(n, "probability"));
            let vehicles = num(n, "number").or(rate.map(|r| r * span)).unwrap_or(0.0);
            (n.attribute("id").unwrap_or("").to_string(), vehicles)
        })
        .collect())
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
    fn flows_are_counted_by_number_or_rate_over_their_span() {
        let cfg = SumoConfig {
            path: "s.sumocfg".into(),
            net: "n.net.xml".into(),
            step_length: 0.2,
            begin: 0.0,
            end: Some(1000.0),
            options: Vec::new(),
        };
        let text = r#"<routes><flow id="n" number="1e9"/><flow id="h" end="3600" vehsPerHour="360"/>
            <flow id="p" begin="500" period="5"/><flow id="q" probability="0.1"/></routes>"#;
        let found = flows(Path::new("r.rou.xml"), text, &cfg).unwrap();
        assert_eq!(
            found,
            [
                ("n".into(), 1e9),
                ("h".into(), 100.0),
                ("p".into(), 100.0),
                ("q".into(), 100.0)
            ]
        );
    }

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
