//! Any SUMO merge network: its edges, lanes, shapes and connections read from the `.net.xml`
//! (what sumolib reads), and the layout found in them: the main carriageway as the chain of
//! edges from its source to its sink, every on-ramp joining it with the acceleration lane it
//! feeds and where that lane ends, and every off-ramp leaving it. A network that is not a
//! one-way carriageway with merges is refused with one line saying what was found.
//!
//! Edge ids are free and internal junction lanes are allowed (netconvert's defaults): the
//! distance along the main carriageway counts the junctions' internal lanes between its edges.
//! The road frame of the layout is built in `road_frame.rs`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::model::math::Point;
use crate::model::reference_line::ReferenceLine;

/// One lane of the network.
#[derive(Debug, Clone, PartialEq)]
pub struct Lane {
    /// SUMO's lane id.
    pub id: String,
    /// Index on its edge (0 = rightmost).
    pub index: u32,
    /// Length (m).
    pub length: f64,
    /// Width (m; SUMO's default 3.2 m when the file gives none).
    pub width: f64,
    /// Speed limit (m/s).
    pub speed: f64,
    /// Centre line in SUMO's plane (m), in driving direction.
    pub shape: Vec<Point>,
}

/// A normal (non-internal) edge and its lanes, rightmost first.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    /// SUMO's edge id.
    pub id: String,
    /// Its lanes, rightmost first.
    pub lanes: Vec<Lane>,
}

/// A lane-to-lane connection between normal edges, through an internal lane (`via`) or not.
#[derive(Debug, Clone, PartialEq)]
pub struct Connection {
    /// Edge the connection leaves.
    pub from: String,
    /// Lane index on `from`.
    pub from_lane: u32,
    /// Edge it enters.
    pub to: String,
    /// Lane index on `to`.
    pub to_lane: u32,
    /// Id of the internal junction lane it runs through, if any.
    pub via: Option<String>,
}

/// What the network file holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Net {
    /// The normal edges.
    pub edges: Vec<Edge>,
    /// Internal junction lanes by id.
    pub internal: BTreeMap<String, Lane>,
    /// The connections between normal edges.
    pub connections: Vec<Connection>,
}

/// Why a network file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum NetworkFileError {
    /// The file could not be read.
    #[error("cannot read network {path}: {cause}")]
    Read {
        /// The network file.
        path: PathBuf,
        /// The operating system's reason.
        cause: std::io::Error,
    },
    #[error("network {path} is not valid XML: {message}")]
    /// The file is not well-formed XML.
    Xml {
        /// The network file.
        path: PathBuf,
        /// The XML parser's message.
        message: String,
    },
    #[error("network {path}: {what}")]
    /// An element lacks an attribute or holds an unreadable value.
    Content {
        /// The network file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    #[error("network {path} is not a one-way carriageway with merges: {what}")]
    /// The network is not a one-way carriageway with merges.
    Layout {
        /// The network file.
        path: PathBuf,
        /// What was found instead.
        what: String,
    },
}

impl Net {
    /// Reads the network file at `path`.
    pub fn read(path: &Path) -> Result<Net, NetworkFileError> {
        let text = std::fs::read_to_string(path).map_err(|cause| NetworkFileError::Read {
            path: path.to_path_buf(),
            cause,
        })?;
        Net::parse(path, &text)
    }

    /// Parses network XML; `path` only names it in errors.
    pub fn parse(path: &Path, text: &str) -> Result<Net, NetworkFileError> {
        let doc = roxmltree::Document::parse(text).map_err(|e| NetworkFileError::Xml {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let bad = |what: String| NetworkFileError::Content {
            path: path.to_path_buf(),
            what,
        };
        let mut net = Net {
            edges: Vec::new(),
            internal: BTreeMap::new(),
            connections: Vec::new(),
        };
        net.read_edges(&doc, &bad)?;
        net.read_connections(&doc, &bad)?;
        Ok(net)
    }

    /// The normal edges (in file order) and the junctions' internal lanes; edges of another
    /// function (walking areas, crossings) are left out.
    fn read_edges(
        &mut self,
        doc: &roxmltree::Document,
        bad: &impl Fn(String) -> NetworkFileError,
    ) -> Result<(), NetworkFileError> {
        for e in doc
            .root_element()
            .children()
            .filter(|n| n.has_tag_name("edge"))
        {
            let id = e
                .attribute("id")
                .ok_or_else(|| bad("an edge without id".into()))?;
            let lanes = e
                .children()
                .filter(|n| n.has_tag_name("lane"))
                .map(|l| lane(l).map_err(|w| bad(format!("edge '{id}': {w}"))))
                .collect::<Result<Vec<Lane>, _>>()?;
            if e.attribute("function") == Some("internal") {
                self.internal
                    .extend(lanes.into_iter().map(|l| (l.id.clone(), l)));
            } else if e.attribute("function").is_none() {
                self.edges.push(Edge {
                    id: id.to_string(),
                    lanes,
                });
            }
        }
        Ok(())
    }

    /// The connections between normal edges (those into or out of an internal lane are the
    /// junction's own and left out).
    fn read_connections(
        &mut self,
        doc: &roxmltree::Document,
        bad: &impl Fn(String) -> NetworkFileError,
    ) -> Result<(), NetworkFileError> {
        let normal: BTreeSet<&str> = self.edges.iter().map(|e| e.id.as_str()).collect();
        let mut connections = Vec::new();
        for c in doc
            .root_element()
            .children()
            .filter(|n| n.has_tag_name("connection"))
        {
            let get = |k: &str| c.attribute(k).unwrap_or_default();
            if !normal.contains(get("from")) || !normal.contains(get("to")) {
                continue; // from or into a junction's internal lane
            }
            let num = |k: &str| {
                get(k).parse::<u32>().map_err(|_| {
                    bad(format!(
                        "connection {} → {}: bad {k}",
                        get("from"),
                        get("to")
                    ))
                })
            };
            connections.push(Connection {
                from: get("from").into(),
                from_lane: num("fromLane")?,
                to: get("to").into(),
                to_lane: num("toLane")?,
                via: c.attribute("via").map(String::from),
            });
        }
        self.connections = connections;
        Ok(())
    }

    fn edge(&self, id: &str) -> &Edge {
        self.edges
            .iter()
            .find(|e| e.id == id)
            .expect("a known edge")
    }

    /// The distinct edges `id` leads to.
    fn successors(&self, id: &str) -> Vec<&str> {
        let set: BTreeSet<&str> = self
            .connections
            .iter()
            .filter(|c| c.from == id)
            .map(|c| c.to.as_str())
            .collect();
        set.into_iter().collect()
    }

    fn has_predecessor(&self, id: &str) -> bool {
        self.connections.iter().any(|c| c.to == id)
    }
}

/// A `<lane>` element.
fn lane(l: roxmltree::Node) -> Result<Lane, String> {
    let num = |k: &str| -> Result<f64, String> {
        l.attribute(k)
            .ok_or_else(|| format!("lane without {k}"))?
            .parse()
            .map_err(|_| format!("lane {k} is not a number"))
    };
    let shape = l
        .attribute("shape")
        .unwrap_or_default()
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').ok_or("bad shape point")?;
            Ok(Point::new(
                x.parse().map_err(|_| "bad shape point")?,
                y.parse().map_err(|_| "bad shape point")?,
            ))
        })
        .collect::<Result<Vec<Point>, &str>>()?;
    Ok(Lane {
        id: l.attribute("id").unwrap_or_default().into(),
        index: num("index")? as u32,
        length: num("length")?,
        // SUMO's default lane width when the attribute is absent.
        width: l.attribute("width").map_or(Ok(3.2), |_| num("width"))?,
        speed: num("speed").unwrap_or(13.89),
        shape,
    })
}

/// An edge of the main carriageway and where it starts along it.
#[derive(Debug, Clone, PartialEq)]
pub struct MainEdge {
    /// SUMO's edge id.
    pub id: String,
    /// Distance along the carriageway to the edge's start (m), internal lanes included.
    pub s_start: f64,
    /// Its length along the carriageway (m), measured on its leftmost lane.
    pub length: f64,
    /// Number of lanes.
    pub lanes: u32,
}

/// An on-ramp: its edges from the source, and the main-road lane it feeds.
#[derive(Debug, Clone, PartialEq)]
pub struct OnRamp {
    /// Its edges from the source, up to the main carriageway (not included).
    pub edges: Vec<String>,
    /// The main edge it joins and the lane of it the ramp's lane continues into.
    pub joins: String,
    /// Lane index on `joins`.
    pub lane: u32,
    /// Where that lane ends along the carriageway (m), if it ends on that edge: the
    /// acceleration lane's end, by which a ramp vehicle must have merged.
    pub merge_end: Option<f64>,
    /// Where that lane starts along the carriageway (m): merging may begin here.
    pub merge_start: f64,
}

/// An off-ramp: the main edge it leaves and its edges to the sink.
#[derive(Debug, Clone, PartialEq)]
pub struct OffRamp {
    /// The main edge it leaves from.
    pub leaves: String,
    /// Its edges, up to the sink.
    pub edges: Vec<String>,
}

/// The merge layout of a network.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// The main carriageway's edges, from source to sink.
    pub main: Vec<MainEdge>,
    /// The on-ramps.
    pub on_ramps: Vec<OnRamp>,
    /// The off-ramps.
    pub off_ramps: Vec<OffRamp>,
    /// The curvilinear frame's reference line: s along it, d from it (positive left).
    pub line: ReferenceLine,
}

impl Layout {
    /// Finds the layout of `net` (read from `path`, named in errors).
    pub fn discover(net: &Net, path: &Path) -> Result<Layout, NetworkFileError> {
        let refuse = |what: String| NetworkFileError::Layout {
            path: path.to_path_buf(),
            what,
        };
        let main_ids = main_chain(net).map_err(refuse)?;
        let line = reference_line(net, &main_ids).map_err(refuse)?;
        let main = positions(net, &main_ids, &line);
        let on_main: BTreeSet<&str> = main_ids.iter().map(String::as_str).collect();
        let mut used: BTreeSet<String> = main_ids.iter().cloned().collect();
        let mut on_ramps = Vec::new();
        for e in net
            .edges
            .iter()
            .filter(|e| !on_main.contains(e.id.as_str()))
        {
            if net.has_predecessor(&e.id) {
                continue;
            }
            let ramp = on_ramp(net, &e.id, &on_main, &line).map_err(refuse)?;
            used.extend(ramp.edges.iter().cloned());
            on_ramps.push(ramp);
        }
        let mut off_ramps = Vec::new();
        for m in &main_ids {
            for next in net.successors(m) {
                if on_main.contains(next) {
                    continue;
                }
                let edges = unique_chain(net, next, &on_main).map_err(refuse)?;
                used.extend(edges.iter().cloned());
                off_ramps.push(OffRamp {
                    leaves: m.clone(),
                    edges,
                });
            }
        }
        if let Some(stray) = net.edges.iter().find(|e| !used.contains(&e.id)) {
            return Err(refuse(format!(
                "edge '{}' is neither on the main carriageway ({}) nor on a ramp",
                stray.id,
                main_ids.join(" → ")
            )));
        }
        Ok(Layout {
            main,
            on_ramps,
            off_ramps,
            line,
        })
    }

    /// What was found, one line per element, for `bkpbs network`.
    pub fn describe(&self) -> String {
        let mut out = format!("main carriageway: {:.2} m\n", self.length());
        for m in &self.main {
            out += &format!(
                "  {:<16} s {:>8.2} – {:>8.2} m  {} lanes\n",
                m.id,
                m.s_start,
                m.s_start + m.length,
                m.lanes
            );
        }
        for (k, r) in self.on_ramps.iter().enumerate() {
            let end = r
                .merge_end
                .map_or("continues (a lane gain)".to_string(), |e| {
                    format!("ends at s {e:.2} m")
                });
            out += &format!(
                "on-ramp {}: {} → {} lane {}: from s {:.2} m, {end}\n",
                k + 1,
                r.edges.join(" → "),
                r.joins,
                r.lane,
                r.merge_start
            );
        }
        for (k, r) in self.off_ramps.iter().enumerate() {
            out += &format!(
                "off-ramp {}: {} → {}\n",
                k + 1,
                r.leaves,
                r.edges.join(" → ")
            );
        }
        out
    }

    /// Length of the main carriageway along the reference line (m).
    pub fn length(&self) -> f64 {
        self.line.length()
    }
}

/// The main carriageway: from the source with the most lanes, at every split the successor
/// with the most lanes, to a sink.
fn main_chain(net: &Net) -> Result<Vec<String>, String> {
    let sources: Vec<&Edge> = net
        .edges
        .iter()
        .filter(|e| !net.has_predecessor(&e.id))
        .collect();
    let start = sources
        .iter()
        .max_by(|a, b| a.lanes.len().cmp(&b.lanes.len()).then(b.id.cmp(&a.id)))
        .ok_or("no edge without a predecessor (a loop?)")?;
    let mut chain = vec![start.id.clone()];
    loop {
        let here = chain.last().expect("non-empty");
        let next = net.successors(here);
        let Some(widest) = next.iter().map(|n| net.edge(n).lanes.len()).max() else {
            return Ok(chain);
        };
        let best: Vec<&&str> = next
            .iter()
            .filter(|n| net.edge(n).lanes.len() == widest)
            .collect();
        if best.len() > 1 {
            return Err(format!(
                "edge '{here}' splits into equally wide edges {:?}: no main carriageway",
                best
            ));
        }
        if chain.iter().any(|c| c == best[0]) {
            return Err(format!("the road loops back to edge '{}'", best[0]));
        }
        chain.push(best[0].to_string());
    }
}

/// The reference line of the main carriageway: the centre line of each main edge's leftmost
/// lane (a through lane: ramps join on the right) and of the internal lane joining it to the
/// next edge's, in order.
fn reference_line(net: &Net, ids: &[String]) -> Result<ReferenceLine, String> {
    let mut points: Vec<Point> = Vec::new();
    for (k, id) in ids.iter().enumerate() {
        let e = net.edge(id);
        let left = e
            .lanes
            .last()
            .ok_or_else(|| format!("edge '{id}' has no lanes"))?;
        points.extend(&left.shape);
        let Some(next) = ids.get(k + 1) else { break };
        let via = net
            .connections
            .iter()
            .filter(|c| &c.from == id && &c.to == next)
            .max_by_key(|c| c.from_lane)
            .and_then(|c| c.via.as_ref())
            .and_then(|v| net.internal.get(v));
        if let Some(lane) = via {
            points.extend(&lane.shape);
        }
    }
    ReferenceLine::new(points).ok_or_else(|| "the main carriageway has no lane shapes".into())
}

/// Where each main edge starts along the reference line.
fn positions(net: &Net, ids: &[String], line: &ReferenceLine) -> Vec<MainEdge> {
    ids.iter()
        .map(|id| {
            let e = net.edge(id);
            let left = e.lanes.last().expect("lanes checked");
            let s_start = left.shape.first().map_or(0.0, |p| line.to_frame(*p).0);
            let s_end = left.shape.last().map_or(0.0, |p| line.to_frame(*p).0);
            MainEdge {
                id: id.clone(),
                s_start,
                length: s_end - s_start,
                lanes: e.lanes.len() as u32,
            }
        })
        .collect()
}

/// The edges from `from` on, each with a single successor, until the main carriageway (not
/// included) or a sink.
fn unique_chain(net: &Net, from: &str, main: &BTreeSet<&str>) -> Result<Vec<String>, String> {
    let mut chain = vec![from.to_string()];
    loop {
        let here = chain.last().expect("non-empty").clone();
        let next = net.successors(&here);
        match next.as_slice() {
            [] => return Ok(chain),
            [n] if main.contains(n) => return Ok(chain),
            [n] if chain.iter().any(|c| c == n) => {
                return Err(format!("ramp edge '{n}' loops"));
            }
            [n] => chain.push(n.to_string()),
            many => return Err(format!("ramp edge '{here}' splits into {many:?}")),
        }
    }
}

/// The on-ramp starting at source edge `source`: where the lane it feeds starts and, if that
/// lane ends on the edge it joins, where it ends, along the reference line.
fn on_ramp(
    net: &Net,
    source: &str,
    on_main: &BTreeSet<&str>,
    line: &ReferenceLine,
) -> Result<OnRamp, String> {
    let edges = unique_chain(net, source, on_main)?;
    let last = edges.last().expect("non-empty");
    let c = net
        .connections
        .iter()
        .find(|c| &c.from == last && on_main.contains(c.to.as_str()))
        .ok_or_else(|| {
            format!("edge '{source}' leads to a sink without joining the main carriageway")
        })?;
    let continues = net
        .connections
        .iter()
        .any(|k| k.from == c.to && k.from_lane == c.to_lane);
    let lane = &net.edge(&c.to).lanes[c.to_lane as usize];
    let at = |p: Option<&Point>| p.map_or(0.0, |p| line.to_frame(*p).0);
    Ok(OnRamp {
        edges,
        joins: c.to.clone(),
        lane: c.to_lane,
        merge_start: at(lane.shape.first()),
        merge_end: (!continues).then(|| at(lane.shape.last())),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str) -> Layout {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("sumo_net/{name}.net.xml"));
        let net = Net::read(&path).unwrap();
        Layout::discover(&net, &path).unwrap()
    }

    fn ids(l: &Layout) -> Vec<&str> {
        l.main.iter().map(|m| m.id.as_str()).collect()
    }

    #[test]
    fn the_paper_net() {
        let l = shipped("merge");
        assert_eq!(ids(&l), ["main_in", "acc", "main_out"]);
        assert_eq!(l.on_ramps.len(), 1);
        let r = &l.on_ramps[0];
        assert_eq!(
            (r.edges.clone(), r.joins.as_str(), r.lane),
            (vec!["ramp".to_string()], "acc", 0)
        );
        assert!((r.merge_start - 150.0).abs() < 1e-6, "{r:?}");
        assert!((r.merge_end.unwrap() - 330.0).abs() < 1e-6, "{r:?}");
        assert!((l.length() - 460.0).abs() < 1e-6);
        assert!(l.off_ramps.is_empty());
        // Straight: s is SUMO's x, as in the fixed frame; the right main lane 4.5 m right of
        // the reference (the left lane's centre line).
        let (s, d) = l.line.to_frame(Point::new(123.4, -6.75));
        assert!(
            (s - 123.4).abs() < 0.01 && (d + 4.5).abs() < 0.01,
            "{s} {d}"
        );
    }

    #[test]
    fn three_lanes_with_internal_lanes() {
        let l = shipped("three-lane");
        assert_eq!(ids(&l), ["hw_a", "hw_merge", "hw_b"]);
        assert_eq!(
            l.main.iter().map(|m| m.lanes).collect::<Vec<_>>(),
            [3, 4, 3]
        );
        let r = &l.on_ramps[0];
        // 200 m, a 3 m internal lane, then the 220 m acceleration lane.
        assert!((r.merge_start - 203.0).abs() < 0.01, "{r:?}");
        assert!((r.merge_end.unwrap() - 423.0).abs() < 0.01, "{r:?}");
        assert!((l.length() - 631.0).abs() < 0.01, "{}", l.length());
        // The acceleration lane's centre: three lanes of 3.6 m right of the reference.
        let (s, d) = l.line.to_frame(Point::new(300.0, 37.4));
        assert!(
            (s - 300.0).abs() < 0.01 && (d + 10.8).abs() < 0.01,
            "{s} {d}"
        );
    }

    #[test]
    fn the_corridor() {
        let l = shipped("corridor");
        assert_eq!(l.on_ramps.len(), 3);
        assert_eq!(l.off_ramps.len(), 2);
        assert_eq!(l.main.first().unwrap().id, "hw0");
        assert_eq!(l.main.last().unwrap().id, "hw5");
        assert!((l.length() - 3000.48).abs() < 0.5, "{}", l.length());
        let ends: Vec<f64> = l.on_ramps.iter().map(|r| r.merge_end.unwrap()).collect();
        assert!(ends.windows(2).all(|w| w[0] < w[1]), "{ends:?}");
        for r in &l.on_ramps {
            let len = r.merge_end.unwrap() - r.merge_start;
            assert!((150.0..260.0).contains(&len), "{r:?}");
        }
        // Curved: the reference turns, and frame and back agree.
        let k: Vec<f64> = (0..30)
            .map(|i| l.line.curvature_at(i as f64 * 100.0).abs())
            .collect();
        assert!(k.iter().any(|&c| c > 1e-4), "{k:?}");
        let p = l.line.to_xy(1234.5, -7.2);
        let (s, d) = l.line.to_frame(p);
        assert!((s - 1234.5).abs() < 0.01 && (d + 7.2).abs() < 0.01);
    }

    /// A two-way road: two carriageways of equal width, neither of which the other joins.
    #[test]
    fn a_two_way_road_is_refused_in_one_line() {
        let xml = r#"<net>
            <edge id="east"><lane id="east_0" index="0" length="100" width="3.5" shape="0,0 100,0"/></edge>
            <edge id="west"><lane id="west_0" index="0" length="100" width="3.5" shape="100,5 0,5"/></edge>
        </net>"#;
        let path = Path::new("two-way.net.xml");
        let net = Net::parse(path, xml).unwrap();
        let e = Layout::discover(&net, path).unwrap_err().to_string();
        assert!(
            e.contains("not a one-way carriageway with merges") && e.contains("'west'"),
            "{e}"
        );
        assert_eq!(e.lines().count(), 1);
        let e = Net::parse(path, "<net><edge").unwrap_err().to_string();
        assert!(e.contains("not valid XML"), "{e}");
    }
}
