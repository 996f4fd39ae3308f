//! Any SUMO network as cars see it: its edges, lanes, shapes and connections read from the
//! `.net.xml` (what sumolib reads), keeping only what a car may drive. Edges closed to cars
//! (footways, cycleways, tracks for pedestrians, rail) are left out with the reason, and so are
//! turnaround connections (a U-turn is no way through a merge, and left in it makes every
//! two-way road a loop). Where the merges lie in it is found in `layout.rs`.
//!
//! Edge ids are free and internal junction lanes are allowed (netconvert's defaults).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

use crate::model::math::Point;

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
    /// Whether a passenger car may drive it (SUMO's `allow` / `disallow`).
    pub for_cars: bool,
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

/// What the network file holds for cars.
#[derive(Debug, Clone, PartialEq)]
pub struct Net {
    /// The normal edges with a lane open to cars.
    pub edges: Vec<Edge>,
    /// Internal junction lanes by id.
    pub internal: BTreeMap<String, Lane>,
    /// The connections between car lanes of normal edges, turnarounds left out.
    pub connections: Vec<Connection>,
    /// The normal edges left out, each with why (closed to cars, and its OSM-style type).
    pub closed: Vec<(String, String)>,
    /// Position of each edge in `edges`, and of each connection in `connections` by the edge
    /// it leaves and the one it enters: the layout asks for them by edge, edge after edge, on
    /// nets of many thousands.
    index: HashMap<String, usize>,
    outgoing: HashMap<String, Vec<usize>>,
    incoming: HashMap<String, Vec<usize>>,
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
}

impl Net {
    /// Reads the network file at `path`.
    pub fn read(path: &Path) -> Result<Net, NetworkFileError> {
        let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Network)
            .map_err(|cause| NetworkFileError::Read {
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
            closed: Vec::new(),
            index: HashMap::new(),
            outgoing: HashMap::new(),
            incoming: HashMap::new(),
        };
        net.read_edges(&doc, &bad)?;
        net.index = (net.edges.iter().enumerate())
            .map(|(k, e)| (e.id.clone(), k))
            .collect();
        net.read_connections(&doc, &bad)?;
        for (k, c) in net.connections.iter().enumerate() {
            net.outgoing.entry(c.from.clone()).or_default().push(k);
            net.incoming.entry(c.to.clone()).or_default().push(k);
        }
        Ok(net)
    }

    /// The normal edges open to cars (in file order) and the junctions' internal lanes; edges
    /// of another function (walking areas, crossings) and edges closed to cars are left out.
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
            } else if e.attribute("function").is_some() {
                continue;
            } else if lanes.iter().any(|l| l.for_cars) {
                self.edges.push(Edge {
                    id: id.to_string(),
                    lanes,
                });
            } else {
                let kind = e
                    .attribute("type")
                    .map_or(String::new(), |t| format!(" ({t})"));
                self.closed
                    .push((id.to_string(), format!("closed to cars{kind}")));
            }
        }
        Ok(())
    }

    /// The connections between car lanes of normal edges (those into or out of an internal
    /// lane are the junction's own, and turnarounds lead back the way a car came: both left
    /// out).
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
                continue; // from or into a junction's internal lane, or a road closed to cars
            }
            if matches!(get("dir"), "t" | "T") {
                continue; // a turnaround
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
            let c = Connection {
                from: get("from").into(),
                from_lane: num("fromLane")?,
                to: get("to").into(),
                to_lane: num("toLane")?,
                via: c.attribute("via").map(String::from),
            };
            if self.lane_for_cars(&c.from, c.from_lane) && self.lane_for_cars(&c.to, c.to_lane) {
                connections.push(c);
            }
        }
        self.connections = connections;
        Ok(())
    }

    fn lane_for_cars(&self, edge: &str, index: u32) -> bool {
        self.index
            .get(edge)
            .and_then(|&k| self.edges[k].lanes.get(index as usize))
            .is_some_and(|l| l.for_cars)
    }

    /// The edge of this id; the caller knows it exists.
    pub(crate) fn edge(&self, id: &str) -> &Edge {
        &self.edges[*self.index.get(id).expect("a known edge")]
    }

    /// The connections leaving edge `id`, in file order.
    pub(crate) fn outgoing(&self, id: &str) -> impl Iterator<Item = &Connection> {
        let at = self.outgoing.get(id).map_or(&[][..], Vec::as_slice);
        at.iter().map(|&k| &self.connections[k])
    }

    /// The connections entering edge `id`, in file order.
    pub(crate) fn incoming(&self, id: &str) -> impl Iterator<Item = &Connection> {
        let at = self.incoming.get(id).map_or(&[][..], Vec::as_slice);
        at.iter().map(|&k| &self.connections[k])
    }

    /// The distinct edges `id` leads to.
    pub(crate) fn successors(&self, id: &str) -> Vec<&str> {
        let set: BTreeSet<&str> = self.outgoing(id).map(|c| c.to.as_str()).collect();
        set.into_iter().collect()
    }

    /// The distinct edges leading to `id`.
    pub(crate) fn predecessors(&self, id: &str) -> Vec<&str> {
        let set: BTreeSet<&str> = self.incoming(id).map(|c| c.from.as_str()).collect();
        set.into_iter().collect()
    }
}

/// A `<lane>` element.
fn lane(l: roxmltree::Node) -> Result<Lane, String> {
    // SUMO asserts on (or silently mis-measures with) lanes of no positive, finite size.
    let num = |k: &str| -> Result<f64, String> {
        l.attribute(k)
            .ok_or_else(|| format!("lane without {k}"))?
            .parse()
            .map_err(|_| format!("lane {k} is not a number"))
    };
    let size = |k: &str| -> Result<f64, String> {
        let x = num(k)?;
        if !(x.is_finite() && x > 0.0) {
            return Err(format!(
                "lane '{}' has {k} {x}: must be a positive, finite number",
                l.attribute("id").unwrap_or_default()
            ));
        }
        Ok(x)
    };
    let shape = l
        .attribute("shape")
        .unwrap_or_default()
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').ok_or("bad shape point")?;
            let coordinate = |v: &str| {
                v.parse::<f64>()
                    .ok()
                    .filter(|c| c.is_finite())
                    .ok_or("bad shape point (not a finite number)")
            };
            Ok(Point::new(coordinate(x)?, coordinate(y)?))
        })
        .collect::<Result<Vec<Point>, &str>>()?;
    Ok(Lane {
        id: l.attribute("id").unwrap_or_default().into(),
        index: num("index")? as u32,
        length: size("length")?,
        // SUMO's default lane width when the attribute is absent.
        width: l.attribute("width").map_or(Ok(3.2), |_| size("width"))?,
        speed: size("speed").unwrap_or(13.89),
        shape,
        for_cars: open_to_cars(l.attribute("allow"), l.attribute("disallow")),
    })
}

/// SUMO's lane permissions for a passenger car: `allow` lists who may (`all` everyone),
/// else `disallow` who may not; neither opens the lane to all.
fn open_to_cars(allow: Option<&str>, disallow: Option<&str>) -> bool {
    let names = |list: &str| {
        list.split_whitespace()
            .any(|c| c == "passenger" || c == "all")
    };
    match (allow, disallow) {
        (Some(a), _) => names(a),
        (None, Some(d)) => !names(d),
        (None, None) => true,
    }
}
