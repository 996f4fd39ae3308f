#!/usr/bin/env python3
"""Adds the `trained_on` record to the committed model and policy files, once.

The files were trained before bkpbs recorded what a file was trained on; what they were
trained on is known from models/README.md, models/profiles/README.md, models/networks/README.md
and results/rl-ppo/README.md, and this script writes it down. What those pages do not say (the
bkpbs version and commit of the training runs) is "not recorded".

The script inserts the key before the file's closing brace and changes no other byte: it checks
that removing what it inserted gives the file back, and refuses a file that has the key already.
Run from the repository's root: python3 scripts/add-trained-on.py
"""

import hashlib
import json
import sys

NOT_RECORDED = "not recorded"
SUMO = "1.15.0"  # Debian's SUMO 1.15.0, the default build, before bkpbs supported another


def record(scenario, seeds, episodes, training_seed, commands):
    # The key order is the Rust struct's (src/config/trained_on.rs), as bkpbs writes it.
    return {
        "step_length_s": 0.2,
        "scenarios": [scenario],
        "episode_seeds": seeds,
        "episodes": episodes,
        "training_seed": training_seed,
        "commands": commands,
        "sumo_version": SUMO,
        "bkpbs_version": NOT_RECORDED,
        "bkpbs_commit": NOT_RECORDED,
    }


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def gcn_records():
    paper = {"kind": "paper-merge"}
    out = {}
    for kind in ["conditioned", "unconditioned"]:
        out[f"models/gcn-{kind}.json"] = record(paper, "10000-10499", "500", "1", [
            "bkpbs collect --episodes 500 --out data/train.bin",
            f"bkpbs train --data data/train.bin --out models/gcn-{kind}.json --{kind} --seed 1 --threads 2",
        ])
        for p in ["paper", "heterogeneous", "krauss", "eidm"]:
            threads = 2 if kind == "conditioned" else 1
            out[f"models/profiles/{p}/gcn-{kind}.json"] = record(paper, "10000-10499", "500", "1", [
                f"bkpbs collect --hdv-profile {p} --episodes 500 --out data/train-{p}.bin",
                f"bkpbs train --data data/train-{p}.bin --out models/profiles/{p}/gcn-{kind}.json --{kind} --seed 1 --threads {threads}",
            ])
        for net in ["three-lane", "corridor"]:
            # The network files are unchanged since before these models were trained.
            scenario = {"kind": "network", "file": f"{net}.net.xml",
                        "sha256": sha256(f"sumo_net/{net}.net.xml")}
            out[f"models/networks/{net}/gcn-{kind}.json"] = record(scenario, "10000-10149", "150", "1", [
                f"bkpbs collect --net sumo_net/{net}.net.xml --episodes 150 --out data/train-net-{net}.bin",
                f"bkpbs train --data data/train-net-{net}.bin --out models/networks/{net}/gcn-{kind}.json --{kind} --seed 1 --threads 2",
            ])
    return out


def policy_record():
    # 1140 updates of 4 episodes, seeds seed_base 1000000 + g (results/rl-ppo/README.md).
    return record({"kind": "paper-merge"}, "1000000-1004559", "4560", "1", [
        "bkpbs train-rl --out results/rl-ppo --steps 10000000",
    ])


def insert(path, rec):
    with open(path, "rb") as f:
        text = f.read()
    if b'"trained_on"' in text:
        sys.exit(f"{path} already has a trained_on record")
    end = text.rindex(b"}")
    added = b',"trained_on":' + json.dumps(rec, ensure_ascii=False, separators=(",", ":")).encode()
    new = text[:end] + added + text[end:]
    assert new[:end] + new[end + len(added):] == text
    json.loads(new)
    with open(path, "wb") as f:
        f.write(new)
    print(f"{path}: +{len(added)} bytes")


def main():
    records = gcn_records()
    records["models/rl-ppo.json"] = policy_record()
    for path, rec in sorted(records.items()):
        insert(path, rec)


if __name__ == "__main__":
    main()
