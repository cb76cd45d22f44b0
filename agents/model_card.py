"""A trained agent's model card (``README.md`` of its folder): the sections of RL Zoo's cards (the agent, usage,
training command, hyperparameters and environment arguments, here as YAML) with the evaluation, and the Hub's metadata
(``huggingface_hub.ModelCardData``: library, tags, and the model-index with the mean reward and the success rate).

Needs ``huggingface_hub`` (the ``zoo`` extra installs it with RL Zoo).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from box_toss_env.files import write_atomic

TEMPLATE = """---
{{ card_data }}
---

# **{{ algo_class }}** Agent playing **{{ env_id }}**

This is a trained model of a **{{ algo_class }}** agent playing **{{ env_id }}** (BoxToss, a Gymnasium environment
on its own rigid-body engine), trained with [Stable-Baselines3](https://github.com/DLR-RM/stable-baselines3) from
hyperparameters in [RL Baselines3 Zoo](https://github.com/DLR-RM/rl-baselines3-zoo)'s format.

## Results

{{ results }}

## Usage

```python
import gymnasium as gym
from agents.pretrained import load_agent

agent = load_agent("{{ env_id }}")  # this folder, its checksums checked
env = gym.make("{{ env_id }}")
obs, info = env.reset(seed=0)
obs, reward, terminated, truncated, info = env.step(agent.predict(obs))
```

`agent.predict` takes the env's observations and returns the env's actions: it normalises the observations with
`vec_normalize.pkl`{{ wrapper }}. The SB3 model alone is `PPO.load("models/{{ folder }}/{{ folder }}.zip")`, on
observations normalised by `vec_normalize.pkl`.

## Training

```bash
{{ command }}
python -m agents.pretrained export RUN   # this folder, evaluated, from the run folder
```

## Hyperparameters

```yaml
{{ hyperparams }}
```

## Environment Arguments

```yaml
{{ env_kwargs }}
```
"""


def results_text(results: dict[str, Any]) -> str:
    """The evaluation in words: success with its interval, and how the agent was trained."""
    low, high = results["success_interval"]
    what = "test episodes" if "mean_height" in results else "test targets"
    text = (
        f"Success on {results['n_eval_episodes']:,} fixed {what} (seeds {results['first_seed']} on, deterministic "
        f"policy): **{results['success_rate']:.1%}** ({results['confidence']:.0%} Wilson interval "
        f"{low:.1%}-{high:.1%}); mean reward {results['mean_reward']:.2f} +/- {results['std_reward']:.2f}."
    )
    if "mean_distance" in results:
        text += (
            f" Mean landing distance {results['mean_distance']:.3f} m, face accuracy {results['face_accuracy']:.1%}."
        )
    return text + (
        f"\n\nTrained for {results['timesteps']:,} throws in {results['train_seconds'] / 60:.1f} min of wall time "
        f"(seed {results['seed']}, one torch thread, on a 2-core CPU shared with other jobs), BoxToss "
        f"{results['version']}."
    )


def card_data(results: dict[str, Any]):
    """The Hub's metadata: library, tags and two evaluation results (mean reward, as RL Zoo's cards, and success)."""
    from huggingface_hub import EvalResult, ModelCardData

    name = f"{results['algo']}-{results['env_id']}"
    common = {
        "task_type": "reinforcement-learning",
        "dataset_type": results["env_id"],
        "dataset_name": results["env_id"],
    }
    return ModelCardData(
        library_name="stable-baselines3",
        tags=[results["env_id"], "deep-reinforcement-learning", "reinforcement-learning", "stable-baselines3"],
        model_name=name,
        eval_results=[
            EvalResult(
                metric_type="mean_reward",
                metric_value=f"{results['mean_reward']:.2f} +/- {results['std_reward']:.2f}",
                **common,
            ),
            EvalResult(metric_type="success_rate", metric_value=round(results["success_rate"], 4), **common),
        ],
    )


def write_model_card(folder: Path, config: dict[str, Any], results: dict[str, Any]) -> Path:
    """``folder/README.md``, written atomically."""
    from huggingface_hub import ModelCard

    hyperparams = {key: value for key, value in config["hyperparams"].items() if key != "env_kwargs"}
    card = ModelCard.from_template(
        card_data(results),
        template_str=TEMPLATE,
        algo_class=config["algo"].upper(),
        env_id=config["env_id"],
        folder=folder.name,
        results=results_text(results),
        wrapper=(
            f" and maps the policy's commands to throws as `{hyperparams['env_wrapper']}` does"
            if hyperparams.get("env_wrapper")
            else "; the policy acts in the env's own actions"
        ),
        command=results["command"],
        hyperparams=yaml.safe_dump(hyperparams, sort_keys=False).strip(),
        env_kwargs=yaml.safe_dump(config.get("env_kwargs", {})).strip(),
    )
    path = folder / "README.md"
    write_atomic(path, str(card) + "\n")
    return path
