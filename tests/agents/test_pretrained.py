"""The trained agents of models/: each folder complete and checksummed, one loads in one line and lands what its
model card says, and a folder that does not match its checksums is refused."""

import json
import shutil

import gymnasium as gym
import numpy as np
import pytest
import yaml

from agents import evaluation
from agents.policies import UnreadableModelError
from agents.pretrained import CHECKSUMS, MODELS, check_folder, load_agent, read_checksums
from agents.variant_gifs import pixel_ids

FILES = {"vec_normalize.pkl", "config.yml", "env_kwargs.yml", "results.json", "README.md"}
FOLDERS = sorted(path for path in MODELS.iterdir() if path.is_dir())


def test_every_variant_with_a_ppo_recipe_has_a_trained_agent():
    recipes = set(yaml.safe_load((MODELS.parent / "agents" / "hyperparams" / "ppo.yml").read_text()))
    recipes -= set(pixel_ids())  # a CnnPolicy's zip is 4.7 MB, past the 1 MB a committed agent may take
    assert {path.name for path in FOLDERS} == {f"ppo-{env_id}" for env_id in recipes}


@pytest.mark.parametrize("folder", FOLDERS, ids=lambda path: path.name)
def test_a_folder_holds_the_hub_layout_and_its_card(folder):
    assert {path.name for path in folder.iterdir()} == FILES | {f"{folder.name}.zip"}
    check_folder(folder)  # every file as its checksum says
    results = json.loads((folder / "results.json").read_text())
    card = (folder / "README.md").read_text()
    low, high = results["success_interval"]
    assert low <= results["success_rate"] <= high
    assert f"**{results['success_rate']:.1%}**" in card and f"{low:.1%}-{high:.1%}" in card
    assert results["command"] in card and "## Hyperparameters" in card and "model-index" in card
    assert (folder / f"{folder.name}.zip").stat().st_size < 1_000_000  # small enough to commit


def test_an_agent_loads_in_one_line_and_lands_what_its_card_says():
    agent = load_agent("BoxToss-ThisSideUp-v0")
    seeds = evaluation.target_seeds(128)
    throws, _ = evaluation.evaluate(agent, "BoxToss-ThisSideUp-v0", seeds=seeds)
    assert agent.results["n_eval_episodes"] == evaluation.TEST_TARGETS
    low, _ = agent.results["success_interval"]
    # the first 128 of the card's 1,024 targets land about as often: at most 3 binomial sd under the interval
    assert throws.success.mean() >= low - 3 * np.sqrt(low * (1 - low) / len(seeds)) - 1e-9


def test_predict_answers_one_observation_or_a_batch_with_the_envs_own_actions():
    agent = load_agent("BoxToss-ShortEnd-v0")
    env = gym.make("BoxToss-ShortEnd-v0")
    observations = np.stack([env.reset(seed=seed)[0] for seed in (10_000, 10_001, 10_002)])
    batch = agent.predict(observations)
    assert batch.shape == (3, 3) and env.action_space.contains(batch[0])
    np.testing.assert_allclose(agent.predict(observations[1]), batch[1], atol=1e-6)  # float32 matmuls of 1 and 3
    env.reset(seed=10_000)
    _, _, terminated, _, info = env.step(batch[0])
    assert terminated and info["success"]  # the card's agent stands the box on an end on this target


def test_a_file_that_does_not_match_its_checksum_is_refused(tmp_path):
    shutil.copytree(MODELS, tmp_path / "models")
    zip_path = tmp_path / "models" / "ppo-BoxToss-v0" / "ppo-BoxToss-v0.zip"
    data = bytearray(zip_path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    zip_path.write_bytes(bytes(data))
    with pytest.raises(UnreadableModelError, match="does not match its checksum"):
        load_agent("BoxToss-v0", models=tmp_path / "models")


def test_an_agent_that_is_not_there_names_those_that_are(tmp_path):
    with pytest.raises(FileNotFoundError, match="ppo-BoxToss-v0"):
        load_agent("BoxToss-Goal-v0")
    assert len(read_checksums()) == len(FOLDERS) * (len(FILES) + 1)
    assert (MODELS / CHECKSUMS).read_text().endswith("\n")


def test_export_makes_a_folder_from_a_run_and_its_card_from_the_evaluation(tmp_path):
    """A run folder (here rebuilt from BoxToss-v0's model) exported: copied, evaluated on the test targets, carded
    and checksummed, as python -m agents.pretrained export does."""
    from agents.pretrained import export, headline_figures

    source = MODELS / "ppo-BoxToss-v0"
    results = json.loads((source / "results.json").read_text())
    run = tmp_path / "run"
    run.mkdir()
    shutil.copyfile(source / "ppo-BoxToss-v0.zip", run / "model.zip")
    shutil.copyfile(source / "vec_normalize.pkl", run / "vecnormalize.pkl")
    shutil.copyfile(source / "config.yml", run / "config.yml")
    (run / "command.txt").write_text("python -m agents.train --env BoxToss-v0\n")
    timing = {"timesteps": results["timesteps"], "wall_seconds": 90.0}
    (run / "timing.json").write_text(json.dumps(timing))
    folder = export(run, tmp_path / "models")
    exported = json.loads((folder / "results.json").read_text())
    assert exported["success_rate"] == results["success_rate"]  # the same model on the same targets
    assert exported["command"] == "python -m agents.train --env BoxToss-v0"
    card = (folder / "README.md").read_text()
    assert "Trained for" in card and "1.5 min of wall time" in card and "```yaml\nn_timesteps:" in card
    check_folder(folder, tmp_path / "models")
    (row,) = headline_figures(tmp_path / "models")
    assert row["env_id"] == "BoxToss-v0" and row["train_time"] == "90 s"


def test_rescore_evaluates_a_committed_agent_again_and_keeps_its_training_figures(tmp_path, capsys):
    """``python -m agents.pretrained rescore`` (after an engine change): the same scores on an unchanged engine,
    the card and checksums rewritten, the training's figures kept; an id without an agent is refused first."""
    from agents.pretrained import main

    models = tmp_path / "models"
    shutil.copytree(MODELS, models)
    folder = models / "ppo-BoxToss-v0"
    before = json.loads((folder / "results.json").read_text())
    written = (models / CHECKSUMS).stat().st_mtime_ns
    with pytest.raises(SystemExit):
        main(["rescore", "BoxToss-v0", "BoxToss-Goal-v0", "--models", str(models)])
    assert "no trained agent of BoxToss-Goal-v0" in capsys.readouterr().err
    assert (models / CHECKSUMS).stat().st_mtime_ns == written  # refused before anything is written
    main(["rescore", "BoxToss-v0", "--models", str(models)])
    after = json.loads((folder / "results.json").read_text())
    assert after == before  # the same model, engine and targets: the same figures
    assert f"**{after['success_rate']:.1%}**" in (folder / "README.md").read_text()
    check_folder(folder, models)  # the checksums follow the new card
