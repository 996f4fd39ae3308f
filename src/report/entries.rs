//! Metrics per entry: the main road and each on-ramp (vehicle ids `main.N`, `ramp.N`, or
//! `ramp1.N`, `ramp2.N`, … on a network of several ramps), per planner, pooled over the whole
//! grid, from a campaign's `vehicles.csv`.

use crate::campaign::results::Results;

/// One (planner, entry) of the table.
#[derive(Debug, Clone, PartialEq)]
pub struct EntryRow {
    pub planner: String,
    pub entry: String,
    pub inserted: usize,
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
    // Planners labelled as in the other tables: with their HDV profile when there are several.
    let several = t
        .rows
        .iter()
        .any(|r| r.cell.hdv_profile != t.rows[0].cell.hdv_profile);
    let label = |r: &crate::campaign::table::Row| match several {
        true => format!("{} ({})", r.cell.planner, r.cell.hdv_profile),
        false => r.cell.planner.clone(),
    };
    let mut out: Vec<(EntryRow, f64)> = Vec::new();
    for r in &t.rows {
        let entry = r
            .fields
            .get(id)
            .unwrap_or("")
            .split('.')
            .next()
            .unwrap_or("");
        let planner = label(r);
        let at = match out
            .iter()
            .position(|(e, _)| e.planner == planner && e.entry == entry)
        {
            Some(k) => k,
            None => {
                out.push((
                    EntryRow {
                        planner,
                        entry: entry.to_string(),
                        inserted: 0,
                        arrived: 0,
                        mean_delay: None,
                        crashed: 0,
                    },
                    0.0,
                ));
                out.len() - 1
            }
        };
        let (row, sum) = &mut out[at];
        let result = r.fields.get(outcome).unwrap_or("");
        row.inserted += usize::from(result != "undeparted");
        row.crashed += usize::from(result == "crashed");
        if let (true, Ok(d)) = (
            result == "arrived",
            r.fields.get(delay).unwrap_or("").parse::<f64>(),
        ) {
            row.arrived += 1;
            *sum += d;
        }
    }
    // Grid order of the planners (then profiles, as they appeared), `main` before the ramps.
    let order = |p: &str| {
        let name = p.split(" (").next().unwrap_or(p);
        res.planners
            .iter()
            .position(|q| q == name)
            .unwrap_or(usize::MAX)
    };
    let mut rows: Vec<EntryRow> = out
        .into_iter()
        .map(|(mut e, sum)| {
            e.mean_delay = (e.arrived > 0).then(|| sum / e.arrived as f64);
            e
        })
        .collect();
    rows.sort_by_key(|e| {
        let natural = (e.entry.len(), e.entry.clone());
        (order(&e.planner), e.entry != "main", natural)
    });
    rows
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
