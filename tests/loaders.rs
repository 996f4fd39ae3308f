//! The configuration and model-file loaders against arbitrary input: random bytes and randomly
//! damaged copies of valid files must give a value or an error, never a panic (a hang would
//! stall this test). A seeded property test: the same inputs every run.

use bkpbs::config::Config;
use bkpbs::predict::model_file::{ModelFile, EMBEDDED_UNCONDITIONED};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Characters that matter to TOML and JSON, and to the numbers in them.
const INTERESTING: &[u8] = b"0123456789-+.eE[]{}=:,\"'\n #xNaninf";

/// `valid` damaged at random: truncated, or with a few bytes replaced, inserted or removed.
fn damaged(valid: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut v = valid.to_vec();
    if rng.gen_bool(0.2) {
        v.truncate(rng.gen_range(0..=v.len()));
        return v;
    }
    for _ in 0..rng.gen_range(1..=4) {
        let at = rng.gen_range(0..=v.len());
        let byte = if rng.gen_bool(0.8) {
            INTERESTING[rng.gen_range(0..INTERESTING.len())]
        } else {
            rng.gen()
        };
        match rng.gen_range(0..3) {
            0 if at < v.len() => v[at] = byte,
            1 => v.insert(at, byte),
            _ if at < v.len() => {
                v.remove(at);
            }
            _ => v.push(byte),
        }
    }
    v
}

fn random_bytes(rng: &mut ChaCha8Rng) -> Vec<u8> {
    let n = rng.gen_range(0..200);
    (0..n).map(|_| rng.gen()).collect()
}

#[test]
fn the_config_loader_answers_every_input_with_a_value_or_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.toml");
    let valid = Config::default().to_toml().into_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let (mut accepted, mut refused) = (0, 0);
    for i in 0..1500 {
        let bytes = if i % 3 == 0 {
            random_bytes(&mut rng)
        } else {
            damaged(&valid, &mut rng)
        };
        std::fs::write(&path, &bytes).unwrap();
        match Config::from_file(&path) {
            // Whatever loads is a configuration that passes every rule and prints.
            Ok(c) => {
                c.validate().unwrap();
                let _ = c.to_toml();
                accepted += 1;
            }
            Err(_) => refused += 1,
        }
    }
    assert!(
        accepted > 0 && refused > 0,
        "{accepted} accepted, {refused} refused"
    );
}

#[test]
fn the_model_loader_answers_every_input_with_a_model_or_an_error() {
    let path = std::path::Path::new("damaged.json");
    let valid = EMBEDDED_UNCONDITIONED.as_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let mut refused = 0;
    for i in 0..120 {
        let bytes = if i % 4 == 0 {
            random_bytes(&mut rng)
        } else {
            damaged(valid, &mut rng)
        };
        let text = String::from_utf8_lossy(&bytes);
        if ModelFile::from_json(path, &text).is_err() {
            refused += 1;
        }
    }
    assert!(refused > 0);
}
