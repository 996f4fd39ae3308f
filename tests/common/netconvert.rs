//! Networks the tests build from plain XML with netconvert.

use std::path::{Path, PathBuf};

/// Writes nodes `(id, x, y)`, edges `(id, from, to, lanes, extra attributes)` and
/// connections `(from, fromLane, to, toLane)` as plain XML and builds the net with netconvert
/// (which adds its own turnarounds at the ends of two-way roads).
pub fn build(
    dir: &Path,
    nodes: &[(&str, f64, f64)],
    edges: &[(&str, &str, &str, u32, &str)],
    cons: &[(&str, u32, &str, u32)],
) -> PathBuf {
    let mut nod = String::from("<nodes>\n");
    for (id, x, y) in nodes {
        nod += &format!("<node id=\"{id}\" x=\"{x}\" y=\"{y}\"/>\n");
    }
    let mut edg = String::from("<edges>\n");
    for (id, from, to, lanes, extra) in edges {
        edg += &format!(
            "<edge id=\"{id}\" from=\"{from}\" to=\"{to}\" numLanes=\"{lanes}\" speed=\"33.33\" {extra}/>\n"
        );
    }
    let mut con = String::from("<connections>\n");
    for (from, fl, to, tl) in cons {
        con += &format!(
            "<connection from=\"{from}\" to=\"{to}\" fromLane=\"{fl}\" toLane=\"{tl}\"/>\n"
        );
    }
    for (name, text) in [
        ("n.nod.xml", nod + "</nodes>\n"),
        ("n.edg.xml", edg + "</edges>\n"),
        ("n.con.xml", con + "</connections>\n"),
    ] {
        std::fs::write(dir.join(name), text).unwrap();
    }
    netconvert(dir, "n");
    dir.join("n.net.xml")
}

/// Builds `NAME.net.xml` in `dir` from its plain XML (`NAME.nod.xml`, `NAME.edg.xml`,
/// `NAME.con.xml`) with netconvert's defaults, as `sumo_net/build_net.sh` builds a layout.
fn netconvert(dir: &Path, name: &str) {
    let file = |kind: &str| format!("{name}.{kind}.xml");
    let status = std::process::Command::new("netconvert")
        .current_dir(dir)
        .args(["-n", &file("nod"), "-e", &file("edg"), "-x", &file("con")])
        .args(["-o", &file("net"), "--no-warnings"])
        .output()
        .expect("netconvert runs");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
}

/// The merge layout `name` of `sumo_net/layouts/` (a SUMO user's scenario: its plain XML, its
/// flows, its configuration) copied into `dir`, its net built there by netconvert: the paths
/// of the net and of the configuration.
pub fn layout(dir: &Path, name: &str) -> (PathBuf, PathBuf) {
    let from = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("sumo_net/layouts")
        .join(name);
    for kind in ["nod.xml", "edg.xml", "con.xml", "rou.xml", "sumocfg"] {
        let file = format!("{name}.{kind}");
        std::fs::copy(from.join(&file), dir.join(&file)).unwrap();
    }
    netconvert(dir, name);
    (
        dir.join(format!("{name}.net.xml")),
        dir.join(format!("{name}.sumocfg")),
    )
}

/// The main lanes of `from` continuing on `to`, aligned on the left.
pub fn through(
    from: &'static str,
    from_lanes: u32,
    to: &'static str,
    to_lanes: u32,
) -> Vec<(&'static str, u32, &'static str, u32)> {
    let n = from_lanes.min(to_lanes);
    (0..n)
        .map(|k| (from, from_lanes - n + k, to, to_lanes - n + k))
        .collect()
}

/// A two-lane motorway (`up`, `acc`, `down`) with an acceleration lane of `acc_length` metres
/// on `acc` that ends, fed by the one-lane ramp `on`.
pub fn merge(dir: &Path, acc_length: f64) -> PathBuf {
    merge_of(dir, 2, 500.0, acc_length)
}

/// A motorway of `lanes` main lanes (`up`, `up_length` metres, `acc`, `down`) with an
/// acceleration lane of `acc_length` metres on `acc` that ends, fed by the one-lane ramp `on`.
pub fn merge_of(dir: &Path, lanes: u32, up_length: f64, acc_length: f64) -> PathBuf {
    let (b, c) = (up_length, up_length + acc_length);
    let nodes = [
        ("a", 0.0, 0.0),
        ("b", b, 0.0),
        ("c", c, 0.0),
        ("d", c + 400.0, 0.0),
        ("r", b - 150.0, -40.0),
    ];
    let edges = [
        ("up", "a", "b", lanes, ""),
        ("acc", "b", "c", lanes + 1, ""),
        ("down", "c", "d", lanes, ""),
        ("on", "r", "b", 1, ""),
    ];
    let mut cons = through("up", lanes, "acc", lanes + 1);
    cons.extend(
        through("acc", lanes + 1, "down", lanes)
            .into_iter()
            .filter(|c| c.1 > 0),
    );
    cons.push(("on", 0, "acc", 0));
    build(dir, &nodes, &edges, &cons)
}

/// What `bkpbs network` prints on `net`, whether it succeeded or not.
pub fn network(net: &Path) -> String {
    let o = super::bkpbs(&["network", net.to_str().unwrap()]);
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        super::stderr(&o)
    )
}
