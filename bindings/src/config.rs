//! The core [`Config`] from what a Python caller passes: a TOML file or TOML text or a nested
//! dict (`config=`), then keyword overrides, merged in that order and checked by the core, so a
//! misspelt key or an invalid value fails exactly as `bkpbs episode --config` fails.

use std::path::{Path, PathBuf};

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use bkpbs::config::Config;

use crate::errors::bad_input;

/// The configuration's top-level tables (`scenario`, `idm`, `planner`, …).
fn sections() -> Vec<String> {
    match toml::Value::try_from(Config::default()) {
        Ok(toml::Value::Table(t)) => t.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

/// A Python value as TOML; `None` for Python's `None` (the key is left unset).
fn to_toml(key: &str, v: &Bound<'_, PyAny>) -> PyResult<Option<toml::Value>> {
    if v.is_none() {
        return Ok(None);
    }
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(Some(toml::Value::Boolean(b.is_true())));
    }
    if v.is_instance_of::<PyInt>() {
        let i: i64 = v
            .extract()
            .map_err(|_| bad_input(format!("config key '{key}': integer out of range")))?;
        return Ok(Some(toml::Value::Integer(i)));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(Some(toml::Value::Float(v.extract()?)));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(Some(toml::Value::String(s.to_cow()?.to_string())));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(Some(toml::Value::Table(dict_to_table(key, d)?)));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, item) in v.try_iter()?.enumerate() {
            if let Some(t) = to_toml(&format!("{key}[{i}]"), &item?)? {
                items.push(t);
            }
        }
        return Ok(Some(toml::Value::Array(items)));
    }
    if v.hasattr("__fspath__")? {
        let p: PathBuf = v.extract()?;
        return Ok(Some(toml::Value::String(p.display().to_string())));
    }
    Err(bad_input(format!(
        "config key '{key}': unsupported value {} of type {}",
        v.repr()?,
        v.get_type().name()?
    )))
}

fn dict_to_table(prefix: &str, d: &Bound<'_, PyDict>) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let Ok(k) = k.extract::<String>() else {
            return Err(bad_input(format!(
                "config keys must be strings, got {}",
                k.repr()?
            )));
        };
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        if let Some(value) = to_toml(&path, &v)? {
            t.insert(k, value);
        }
    }
    Ok(t)
}

/// Merges `over` into `base`, table by table.
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

fn parse_toml(text: &str, path: Option<&Path>) -> PyResult<toml::Table> {
    toml::from_str(text).map_err(|e| {
        let message = e.message().to_string()
            + &e.span()
                .map(|s| format!(" (at byte {})", s.start))
                .unwrap_or_default();
        match path {
            Some(p) => bad_input(format!("malformed config file {}: {message}", p.display())),
            None => bad_input(format!("malformed TOML configuration: {message}")),
        }
    })
}

fn read_file(path: &Path) -> PyResult<toml::Table> {
    let text = bkpbs::io::bounded::read_text(path, bkpbs::io::bounded::FileKind::Config)
        .map_err(|e| bad_input(format!("cannot read config file {}: {e}", path.display())))?;
    parse_toml(&text, Some(path))
}

/// The `config=` argument as a table: a dict, TOML text, or the path of a TOML file (a `str`
/// naming an existing file or ending in `.toml`, or any path-like object).
fn source_table(config: &Bound<'_, PyAny>) -> PyResult<toml::Table> {
    if let Ok(d) = config.cast::<PyDict>() {
        return dict_to_table("", d);
    }
    if let Ok(s) = config.cast::<PyString>() {
        let s = s.to_cow()?;
        let s: &str = &s;
        let p = Path::new(s);
        if !s.contains('\n') && (p.is_file() || s.ends_with(".toml")) {
            return read_file(p);
        }
        return parse_toml(s, None);
    }
    if config.hasattr("__fspath__")? {
        let p: PathBuf = config.extract()?;
        return read_file(&p);
    }
    Err(bad_input(format!(
        "config must be a dict, TOML text or the path of a TOML file, got {}",
        config.get_type().name()?
    )))
}

/// Keyword overrides as a table: a section name takes a dict (`idm={"accel": 2.0}`), any other
/// key is a `scenario` setting (`steps=100`).
fn overrides_table(overrides: &Bound<'_, PyDict>) -> PyResult<toml::Table> {
    let sections = sections();
    let mut out = toml::Table::new();
    let mut scenario = toml::Table::new();
    for (k, v) in overrides.iter() {
        let k: String = k.extract()?;
        if sections.contains(&k) {
            let d = v.cast::<PyDict>().map_err(|_| {
                bad_input(format!(
                    "config section '{k}' must be given as a dict, e.g. {k}={{...}}"
                ))
            })?;
            out.insert(k.clone(), toml::Value::Table(dict_to_table(&k, d)?));
        } else if let Some(value) = to_toml(&format!("scenario.{k}"), &v)? {
            scenario.insert(k, value);
        }
    }
    if !scenario.is_empty() {
        merge(
            &mut out,
            toml::Table::from_iter([("scenario".to_string(), toml::Value::Table(scenario))]),
        );
    }
    Ok(out)
}

/// Defaults ← `config` ← keyword `overrides` ← `scenario` (e.g. α, λ and the seed given as
/// arguments), deserialised and validated by the core.
///
/// # Errors
/// [`crate::errors::BkpbsError`] for an unreadable or malformed source, an unknown key, a wrong
/// type or an invalid value.
pub fn resolve(
    config: Option<&Bound<'_, PyAny>>,
    overrides: Option<&Bound<'_, PyDict>>,
    scenario: toml::Table,
) -> PyResult<Config> {
    let mut table = match config {
        Some(c) if !c.is_none() => source_table(c)?,
        _ => toml::Table::new(),
    };
    if let Some(o) = overrides {
        merge(&mut table, overrides_table(o)?);
    }
    if !scenario.is_empty() {
        merge(
            &mut table,
            toml::Table::from_iter([("scenario".to_string(), toml::Value::Table(scenario))]),
        );
    }
    let config: Config =
        toml::Value::Table(table.clone())
            .try_into()
            .map_err(|e: toml::de::Error| {
                // serde does not say where: find the first section that fails on its own.
                let section = table.iter().find_map(|(k, v)| {
                    let alone = toml::Table::from_iter([(k.clone(), v.clone())]);
                    toml::Value::Table(alone)
                        .try_into::<Config>()
                        .is_err()
                        .then(|| format!(" [{k}]"))
                });
                bad_input(format!(
                    "invalid configuration{}: {}",
                    section.unwrap_or_default(),
                    e.message().trim()
                ))
            })?;
    config.validate().map_err(bad_input)?;
    Ok(config)
}
