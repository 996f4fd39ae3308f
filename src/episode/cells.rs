//! A serde struct read as one flat record: its fields, in order, as named and typed cells
//! (the fields of a nested struct inline, under their own names).
//!
//! Why it exists: the episode summary is defined once, as a struct, and everything that shows
//! it — the `episode.csv` header and row, the campaign's checks of `episodes.csv`, the Python
//! bindings' typed dict — reads it through this one serializer, so a metric is added in one
//! place. The `csv` crate's own serde support does not fit: it writes no header for a nested
//! struct, and it formats floats its own way, while `episode.csv` keeps a fixed number of
//! decimals per column. That number is part of the struct's definition: a field marked
//! `#[serde(serialize_with = "decimals::<4, _>")]` (or [`opt_decimals`]) carries it to
//! [`Value::Float`]; an unmarked float is written in Rust's shortest form (`{}`).
//!
//! A file's columns are those of a template row, worked out once and kept: [`columns_once`],
//! or per traffic [`TrafficColumns`] where the traffic decides the row's parts.

use std::sync::OnceLock;

use serde::ser::{self, Impossible, Serialize, Serializer};

use crate::episode::traffic::Traffic;

/// One cell's value, as the struct holds it.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A string or char (also a unit enum variant, by its serde name).
    Text(String),
    /// A signed integer.
    Int(i64),
    /// An unsigned integer.
    UInt(u64),
    /// A boolean (`true` / `false`).
    Bool(bool),
    /// `decimals`: the fixed decimals of the CSV text, `None` for the shortest form.
    Float {
        /// The number.
        value: f64,
        /// Fixed decimals of its CSV text; `None`: Rust's shortest form.
        decimals: Option<usize>,
    },
    /// An absent optional value (an empty CSV field).
    Empty,
}

impl Value {
    /// The CSV text of the value.
    pub fn csv_text(&self) -> String {
        match self {
            Value::Text(s) => s.clone(),
            Value::Int(i) => i.to_string(),
            Value::UInt(u) => u.to_string(),
            Value::Bool(b) => b.to_string(),
            Value::Float {
                value,
                decimals: Some(d),
            } => format!("{value:.d$}"),
            Value::Float {
                value,
                decimals: None,
            } => format!("{value}"),
            Value::Empty => String::new(),
        }
    }
}

/// One named cell of a record.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// The column name: the field's serde name.
    pub column: &'static str,
    /// The field's value.
    pub value: Value,
}

/// Why a value is not a flat record (a sequence, a map, an enum with data, bytes).
#[derive(Debug, thiserror::Error)]
#[error("not a flat record: {0}")]
pub struct RecordError(String);

impl ser::Error for RecordError {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        RecordError(msg.to_string())
    }
}

/// The cells of a struct, in field order.
pub fn cells<T: Serialize>(record: &T) -> Result<Vec<Cell>, RecordError> {
    let mut out = Vec::new();
    record.serialize(Flatten {
        out: &mut out,
        column: "",
        decimals: None,
    })?;
    Ok(out)
}

/// The columns of `record`, in field order.
pub fn columns_of<T: Serialize>(record: &T) -> Vec<&'static str> {
    let cells = cells(record).expect("a flat record");
    cells.into_iter().map(|c| c.column).collect()
}

/// The columns of `template()`, worked out on the first call and kept in `list`.
pub fn columns_once<'a, T: Serialize>(
    list: &'a OnceLock<Vec<&'static str>>,
    template: impl FnOnce() -> T,
) -> &'a [&'static str] {
    list.get_or_init(|| columns_of(&template()))
}

/// The columns of a record's template row for each [`Traffic`] (whose parts differ), each
/// list worked out on first use and kept: a `static` behind a `columns(traffic)`.
pub struct TrafficColumns<T> {
    template: fn(Traffic) -> T,
    demand: OnceLock<Vec<&'static str>>,
    scenario: OnceLock<Vec<&'static str>>,
}

impl<T: Serialize> TrafficColumns<T> {
    /// The columns of `template(traffic)`, none worked out yet.
    pub const fn new(template: fn(Traffic) -> T) -> Self {
        TrafficColumns {
            template,
            demand: OnceLock::new(),
            scenario: OnceLock::new(),
        }
    }

    /// The columns of `traffic`'s template row, in order.
    pub fn of(&self, traffic: Traffic) -> &[&'static str] {
        let list = match traffic {
            Traffic::Demand => &self.demand,
            Traffic::Scenario => &self.scenario,
        };
        columns_once(list, || (self.template)(traffic))
    }
}

/// The CSV text of `rows`, under the columns of `template` (a record with every part the
/// rows have: a part a row lacks is no column).
pub fn csv_text<T: Serialize>(template: &T, rows: &[T]) -> Vec<u8> {
    let header = columns_of(template);
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&header).expect("writing to memory");
    for r in rows {
        let row: Vec<String> = cells(r)
            .expect("a flat record")
            .iter()
            .map(|c| c.value.csv_text())
            .collect();
        w.write_record(&row).expect("writing to memory");
    }
    w.into_inner().expect("writing to memory")
}

/// Newtype names that carry a float's decimals ([`Decimals`]); the index is the count.
const DECIMALS: [&str; 7] = [
    "decimals:0",
    "decimals:1",
    "decimals:2",
    "decimals:3",
    "decimals:4",
    "decimals:5",
    "decimals:6",
];

/// A float written with `N` decimals (up to 6); other serializers see the plain float.
pub struct Decimals<const N: usize>(pub f64);

impl<const N: usize> Serialize for Decimals<N> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_newtype_struct(DECIMALS[N], &self.0)
    }
}

/// `serialize_with` for an `f64` field written with `N` decimals.
pub fn decimals<const N: usize, S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    Decimals::<N>(*x).serialize(s)
}

/// `serialize_with` for an `Option<f64>` field written with `N` decimals (empty if `None`).
pub fn opt_decimals<const N: usize, S: Serializer>(
    x: &Option<f64>,
    s: S,
) -> Result<S::Ok, S::Error> {
    match x {
        Some(v) => s.serialize_some(&Decimals::<N>(*v)),
        None => s.serialize_none(),
    }
}

/// Appends the cells of what it serializes to `out`; a scalar becomes the cell `column`.
struct Flatten<'a> {
    out: &'a mut Vec<Cell>,
    column: &'static str,
    decimals: Option<usize>,
}

impl Flatten<'_> {
    fn push(self, value: Value) -> Result<(), RecordError> {
        self.out.push(Cell {
            column: self.column,
            value,
        });
        Ok(())
    }
}

/// The fields of a (possibly nested) struct, each flattened in turn.
struct Fields<'a> {
    out: &'a mut Vec<Cell>,
}

impl ser::SerializeStruct for Fields<'_> {
    type Ok = ();
    type Error = RecordError;

    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), RecordError> {
        value.serialize(Flatten {
            out: self.out,
            column: key,
            decimals: None,
        })
    }

    fn end(self) -> Result<(), RecordError> {
        Ok(())
    }
}

fn unsupported<T>(what: &str) -> Result<T, RecordError> {
    Err(RecordError(format!("{what} is not a cell")))
}

impl<'a> Serializer for Flatten<'a> {
    type Ok = ();
    type Error = RecordError;
    type SerializeSeq = Impossible<(), RecordError>;
    type SerializeTuple = Impossible<(), RecordError>;
    type SerializeTupleStruct = Impossible<(), RecordError>;
    type SerializeTupleVariant = Impossible<(), RecordError>;
    type SerializeMap = Impossible<(), RecordError>;
    type SerializeStruct = Fields<'a>;
    type SerializeStructVariant = Impossible<(), RecordError>;

    fn serialize_bool(self, v: bool) -> Result<(), RecordError> {
        self.push(Value::Bool(v))
    }
    fn serialize_i8(self, v: i8) -> Result<(), RecordError> {
        self.serialize_i64(v.into())
    }
    fn serialize_i16(self, v: i16) -> Result<(), RecordError> {
        self.serialize_i64(v.into())
    }
    fn serialize_i32(self, v: i32) -> Result<(), RecordError> {
        self.serialize_i64(v.into())
    }
    fn serialize_i64(self, v: i64) -> Result<(), RecordError> {
        self.push(Value::Int(v))
    }
    fn serialize_u8(self, v: u8) -> Result<(), RecordError> {
        self.serialize_u64(v.into())
    }
    fn serialize_u16(self, v: u16) -> Result<(), RecordError> {
        self.serialize_u64(v.into())
    }
    fn serialize_u32(self, v: u32) -> Result<(), RecordError> {
        self.serialize_u64(v.into())
    }
    fn serialize_u64(self, v: u64) -> Result<(), RecordError> {
        self.push(Value::UInt(v))
    }
    fn serialize_f32(self, v: f32) -> Result<(), RecordError> {
        self.serialize_f64(v.into())
    }
    fn serialize_f64(self, v: f64) -> Result<(), RecordError> {
        let decimals = self.decimals;
        self.push(Value::Float { value: v, decimals })
    }
    fn serialize_char(self, v: char) -> Result<(), RecordError> {
        self.push(Value::Text(v.to_string()))
    }
    fn serialize_str(self, v: &str) -> Result<(), RecordError> {
        self.push(Value::Text(v.to_string()))
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<(), RecordError> {
        unsupported("bytes")
    }
    fn serialize_none(self) -> Result<(), RecordError> {
        self.push(Value::Empty)
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<(), RecordError> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<(), RecordError> {
        self.push(Value::Empty)
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), RecordError> {
        self.push(Value::Empty)
    }
    fn serialize_unit_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
    ) -> Result<(), RecordError> {
        self.serialize_str(variant)
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        v: &T,
    ) -> Result<(), RecordError> {
        let decimals = DECIMALS.iter().position(|d| *d == name).or(self.decimals);
        v.serialize(Flatten { decimals, ..self })
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<(), RecordError> {
        unsupported("an enum with data")
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq, RecordError> {
        unsupported("a sequence")
    }
    fn serialize_tuple(self, _: usize) -> Result<Self::SerializeTuple, RecordError> {
        unsupported("a tuple")
    }
    fn serialize_tuple_struct(
        self,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleStruct, RecordError> {
        unsupported("a tuple struct")
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, RecordError> {
        unsupported("an enum with data")
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, RecordError> {
        unsupported("a map")
    }
    fn serialize_struct(
        self,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStruct, RecordError> {
        Ok(Fields { out: self.out })
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, RecordError> {
        unsupported("an enum with data")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    struct Inner {
        #[serde(rename = "inner_count")]
        count: u32,
    }

    #[derive(serde::Serialize)]
    struct Outer {
        name: String,
        shortest: f64,
        #[serde(serialize_with = "decimals::<2, _>")]
        two: f64,
        #[serde(serialize_with = "opt_decimals::<4, _>")]
        missing: Option<f64>,
        #[serde(serialize_with = "opt_decimals::<4, _>")]
        present: Option<f64>,
        inner: Inner,
    }

    #[test]
    fn nested_fields_inline_with_their_decimals() {
        let c = cells(&Outer {
            name: "a".into(),
            shortest: 3000.0,
            two: 1.0 / 3.0,
            missing: None,
            present: Some(2.5),
            inner: Inner { count: 7 },
        })
        .unwrap();
        let columns: Vec<_> = c.iter().map(|c| c.column).collect();
        assert_eq!(
            columns,
            [
                "name",
                "shortest",
                "two",
                "missing",
                "present",
                "inner_count"
            ]
        );
        let text: Vec<_> = c.iter().map(|c| c.value.csv_text()).collect();
        assert_eq!(text, ["a", "3000", "0.33", "", "2.5000", "7"]);
        assert_eq!(
            c[2].value,
            Value::Float {
                value: 1.0 / 3.0,
                decimals: Some(2)
            }
        );
    }

    #[test]
    fn sequences_are_refused() {
        assert!(cells(&vec![1, 2]).is_err());
    }
}
