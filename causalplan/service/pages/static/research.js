// The research pages' script: "Watch the robot" plays a trial's plan in 3D (robot_player.js).
//
// Each player's box holds the object and the fits of the plan (data-object, data-fits); a click
// asks POST /research/playback for the robot's run while the player's libraries load, as a
// participant's step 2 does.

async function playback(object, fits) {
  const response = await fetch("/research/playback", {
    method: "POST",
    headers: { "Content-Type": "application/json", Accept: "application/json" },
    body: JSON.stringify({ object: object, fits: fits }),
    credentials: "same-origin",
  });
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

function watchable(box) {
  const watch = box.querySelector("button.watch-robot");
  const stage = box.querySelector(".robot-player");
  const note = stage.querySelector("[role=status]");
  watch.addEventListener("click", async function () {
    watch.disabled = true;
    note.textContent = "The robot is working out its motions…";
    try {
      const [player, run] = await Promise.all([
        import("/web/static/robot_player.js").then(function (module) {
          module.loadPanda(); // the arm's meshes load while the robot works out its motions
          return module;
        }),
        playback(box.dataset.object, JSON.parse(box.dataset.fits)),
      ]);
      await player.createPlayer(stage, run);
      note.remove();
      watch.remove();
      if (run.outcome && !run.outcome.carried_out && run.outcome.reason) {
        const why = document.createElement("p");
        why.className = "feedback";
        why.textContent = run.outcome.reason.message;
        box.appendChild(why);
      }
    } catch (error) {
      note.textContent = "The robot cannot be shown now: " + error.message;
      watch.disabled = false;
    }
  });
}

document.querySelectorAll(".robot-film[data-fits]").forEach(watchable);
