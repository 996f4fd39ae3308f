//! Generalised advantage estimation (Schulman et al. 2016) over one agent's segment.

use super::Segment;

/// Advantages and value targets (returns) of every step of `seg`: δ_t = r_t + γ V(s_{t+1}) −
/// V(s_t), A_t = δ_t + γλ A_{t+1}, R_t = A_t + V(s_t); after the last step V is 0 if the
/// segment is terminal, else its bootstrap value.
pub fn advantages(seg: &Segment, gamma: f32, lambda: f32) -> (Vec<f32>, Vec<f32>) {
    let n = seg.steps.len();
    let mut adv = vec![0.0f32; n];
    let mut next_adv = 0.0f32;
    for t in (0..n).rev() {
        let next_value = if t + 1 < n {
            seg.steps[t + 1].value
        } else if seg.terminal {
            0.0
        } else {
            seg.bootstrap
        };
        let s = &seg.steps[t];
        let delta = s.reward + gamma * next_value - s.value;
        next_adv = delta + gamma * lambda * next_adv;
        adv[t] = next_adv;
    }
    let returns = adv
        .iter()
        .zip(&seg.steps)
        .map(|(a, s)| a + s.value)
        .collect();
    (adv, returns)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::train::ppo::Step;

    fn step(reward: f32, value: f32) -> Step {
        Step {
            obs: vec![],
            mask: vec![true],
            action: 0,
            log_prob: 0.0,
            value,
            reward,
            forced: false,
        }
    }

    #[test]
    fn hand_computed() {
        // γ = 0.5, λ = 1: δ1 = 2 + 0.5·0 − 1 = 1 (terminal), δ0 = 1 + 0.5·1 − 0 = 1.5,
        // A1 = 1, A0 = 1.5 + 0.5·1 = 2; returns = A + V = (2, 2).
        let seg = Segment {
            steps: vec![step(1.0, 0.0), step(2.0, 1.0)],
            terminal: true,
            bootstrap: 99.0,
        };
        let (a, r) = advantages(&seg, 0.5, 1.0);
        assert_eq!(a, vec![2.0, 1.0]);
        assert_eq!(r, vec![2.0, 2.0]);
        // Truncated: the bootstrap value 4 enters δ1 = 2 + 2 − 1 = 3.
        let seg = Segment {
            terminal: false,
            bootstrap: 4.0,
            ..seg
        };
        assert_eq!(advantages(&seg, 0.5, 1.0).0, vec![3.0, 3.0]);
    }
}
