//! Metrics per entry: the main road and each on-ramp (vehicle ids `main.N`, `ramp.N`, or
//! `ramp1.N`, `ramp2.N`, … on a network of several ramps), per planner, pooled over the whole
//! grid, from a campaign's `vehicles.csv`.

use crate::campaign::results::Results;
use crate::campaign::table::Row;

/// One (planner, entry) of the table.
#[derive(Debug, Clone, PartialEq)]
pub struct EntryRow {
    /// The planner, with its HDV profile in brackets when the results hold several profiles.
    pub planner: String,
    /// Where the vehicles entered: the prefix of their ids (`main`, `ramp`, `ramp1`, …).
    pub entry: String,
    /// Vehicles that entered the network (every outcome but `never_inserted`).
    pub inserted: usize,
    /// Vehicles that reached the end of their route.
    pub arrived: usize,
    /// Mean travel delay of the vehicles that arrived (s).
    pub mean_delay: Option<f64>,
    /// Vehicles removed in collisions.
    pub crashed: usize,
}

/// The rows, planners in grid order, then `main` and the ramps in their order along the road.
pub fn rows(res: &Results) -> Vec<EntryRow> {
    let t = &res.vehicles;
    let (Some(id), Some(outcome), Some(delay)) =
        (t.column("id"), t.column("outcome"), t.column("delay_s"))
    else {
        return Vec::new();
    };
    let several_profiles = t
        .rows
        .iter()
        .any(|r| r.cell.hdv_profile != t.rows[0].cell.hdv_profile);
    let mut tallies: Vec<Tally> = Vec::new();
    for r in &t.rows {
        let field = |k: usize| r.fields.get(k).unwrap_or("");
        let planner = planner_label(r, several_profiles);
        Tally::find_or_add(&mut tallies, planner, entry_of(field(id)))
            .count(field(outcome), field(delay));
    }
    let mut rows: Vec<EntryRow> = tallies.into_iter().map(Tally::finish).collect();
    sort_in_grid_order(&mut rows, &res.planners);
    rows
}

/// The entry a vehicle id names: the part before the first dot (`ramp1.7` is `ramp1`).
fn entry_of(id: &str) -> &str {
    id.split('.').next().unwrap_or("")
}

/// The planner labelled as in the other tables: with its HDV profile when there are several.
fn planner_label(r: &Row, several_profiles: bool) -> String {
    match several_profiles {
        true => format!("{} ({})", r.cell.planner, r.cell.hdv_profile),
        false => r.cell.planner.clone(),
    }
}

/// A row being counted, with the sum of its arrived vehicles' delays.
struct Tally {
    row: EntryRow,
    delay_sum: f64,
}

impl Tally {
    /// The tally of (`planner`, `entry`), appended empty if it is the first of its vehicles.
    fn find_or_add<'t>(tallies: &'t mut Vec<Tally>, planner: String, entry: &str) -> &'t mut Tally {
        let at = tallies
            .iter()
            .position(|t| t.row.planner == planner && t.row.entry == entry);
        let at = at.unwrap_or_else(|| {
            tallies.push(Tally {
                row: EntryRow {
                    planner,
                    entry: entry.to_string(),
                    inserted: 0,
                    arrived: 0,
                    mean_delay: None,
                    crashed: 0,
                },
                delay_sum: 0.0,
            });
            tallies.len() - 1
        });
        &mut tallies[at]
    }

    /// Counts one vehicle by its `outcome` and `delay_s` fields.
    fn count(&mut self, outcome: &str, delay: &str) {
        self.row.inserted += usize::from(outcome != "never_inserted");
        self.row.crashed += usize::from(outcome == "crashed");
        if let (true, Ok(d)) = (outcome == "arrived", delay.parse::<f64>()) {
            self.row.arrived += 1;
            self.delay_sum += d;
        }
    }

    /// The row, its mean delay over the vehicles that arrived.
    fn finish(self) -> EntryRow {
        let Tally { mut row, delay_sum } = self;
        row.mean_delay = (row.arrived > 0).then(|| delay_sum / row.arrived as f64);
        row
    }
}

/// Grid order of the planners (then profiles, as they appeared), `main` before the ramps, the
/// ramps in natural order (`ramp2` before `ramp10`).
fn sort_in_grid_order(rows: &mut [EntryRow], planners: &[String]) {
    let order = |p: &str| {
        let name = p.split(" (").next().unwrap_or(p);
        planners
            .iter()
            .position(|q| q == name)
            .unwrap_or(usize::MAX)
    };
    rows.sort_by_key(|e| {
        let natural = (e.entry.len(), e.entry.clone());
        (order(&e.planner), e.entry != "main", natural)
    });
}

/// The rows as `delay_by_entry.csv`.
pub fn csv(rows: &[EntryRow]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "planner",
        "entry",
        "inserted",
        "arrived",
        "crashed",
        "mean_delay_s",
    ])
    .expect("writing to memory");
    for e in rows {
        let delay = e.mean_delay.map_or(String::new(), |d| format!("{d:.4}"));
        w.write_record([
            e.planner.clone(),
            e.entry.clone(),
            e.inserted.to_string(),
            e.arrived.to_string(),
            e.crashed.to_string(),
            delay,
        ])
        .expect("writing to memory");
    }
    w.into_inner().expect("writing to memory")
}

/// The Markdown section: one row per planner, a column per entry.
pub fn markdown(rows: &[EntryRow]) -> String {
    let mut entries: Vec<&str> = Vec::new();
    let mut planners: Vec<&str> = Vec::new();
    for e in rows {
        if !entries.contains(&e.entry.as_str()) {
            entries.push(&e.entry);
        }
        if !planners.contains(&e.planner.as_str()) {
            planners.push(&e.planner);
        }
    }
    let mut md = String::from("## Mean travel delay by entry (s)\n\n");
    md += "Over every vehicle of the grid that arrived, by where it entered (arrived / inserted \
           in brackets).\n\n";
    md += &format!("| planner | {} |\n", entries.join(" | "));
    md += &format!("| --- |{}\n", " ---: |".repeat(entries.len()));
    for p in planners {
        md += &format!("| {p} |");
        for entry in &entries {
            let cell = rows
                .iter()
                .find(|e| e.planner == p && e.entry == *entry)
                .map_or("–".to_string(), |e| {
                    let d = e.mean_delay.map_or("–".to_string(), |d| format!("{d:.2}"));
                    format!("{d} ({}/{})", e.arrived, e.inserted)
                });
            md += &format!(" {cell} |");
        }
        md += "\n";
    }
    md + "\n"
}
