// The research page "Watch the robot repair an object": the 3D player (robot_player.js) on a robot
// troubleshooting episode.
//
// The form names an object's broken part and a strategy. The script posts them, with the object's
// reference model (in the page, #reference-models), to POST /v1/troubleshooting with `robot` (a job),
// follows the job while the player's libraries load, then opens the player on the job's document
// (GET /v1/jobs/{id}/playback), which lists each action of the episode as it plays.

const POLL_MILLISECONDS = 1000;
const UNFINISHED = ["queued", "running"];

const form = document.getElementById("repair-form");
const watch = document.getElementById("repair-watch");
const note = document.getElementById("repair-status");
const stage = document.getElementById("repair-player");
const models = JSON.parse(document.getElementById("reference-models").textContent);

// The answer's JSON; an answer that is not OK throws its error's message.
async function answer(response) {
  let data = null;
  try {
    data = await response.json();
  } catch (error) {
    data = null;
  }
  if (!response.ok) {
    throw new Error(data && data.error ? data.error.message : "The server answered " + response.status + ".");
  }
  return data;
}

function sleep(milliseconds) {
  return new Promise(function (resolve) { setTimeout(resolve, milliseconds); });
}

// The finished job: asked again until it is neither queued nor running.
async function finished(job) {
  while (UNFINISHED.includes(job.status)) {
    const done = job.progress.total ? " (" + job.progress.done + " of " + job.progress.total + ")" : "";
    note.textContent = "The robot is carrying out the episode: " + job.status + done + "…";
    await sleep(POLL_MILLISECONDS);
    job = await answer(await fetch(job.url, { headers: { Accept: "application/json" } }));
  }
  return job;
}

async function repair(objectId, part, strategy) {
  const body = { model: models[objectId], object: objectId, fault: part, strategy: strategy, robot: true };
  const posted = await fetch("/v1/troubleshooting", {
    method: "POST",
    headers: { "Content-Type": "application/json", Accept: "application/json" },
    body: JSON.stringify(body),
  });
  const job = await finished(await answer(posted));
  if (job.status !== "succeeded") {
    throw new Error(job.error ? job.error.message : "the job was " + job.status + ".");
  }
  if (!job.result.playback) {
    throw new Error("the robot stopped before it moved: " + describe(job.result.robot.actions));
  }
  const run = await answer(await fetch(job.result.playback.url, { headers: { Accept: "application/json" } }));
  return { result: job.result, run: run };
}

// Why the robot stopped: the first action it could not do.
function describe(actions) {
  const failed = actions.find(function (action) { return !action.passed; });
  return failed ? failed.message || failed.failure : "no action failed.";
}

form.addEventListener("submit", async function (event) {
  event.preventDefault();
  const chosen = form.elements.fault.selectedOptions[0];
  watch.disabled = true;
  note.textContent = "The robot is carrying out the episode…";
  stage.replaceChildren(); // a new run replaces the one shown
  try {
    const [player, repaired] = await Promise.all([
      import("/web/static/robot_player.js").then(function (module) {
        module.loadPanda(); // the arm's meshes load while the robot works
        return module;
      }),
      repair(chosen.dataset.object, chosen.dataset.part, form.elements.strategy.value),
    ]);
    const box = document.createElement("div");
    stage.append(box);
    await player.createPlayer(box, repaired.run);
    const result = repaired.result;
    note.textContent = result.status === "repaired"
      ? "The robot repaired the " + repaired.run.name + " in " + result.episode.actions + " actions."
      : "The robot did not repair the " + repaired.run.name + " in physics: " + describe(result.robot.actions);
  } catch (error) {
    note.textContent = "The robot cannot be shown now: " + error.message;
  } finally {
    watch.disabled = false;
  }
});
