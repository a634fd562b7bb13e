// The participant pages' script: save as one types, check rules live, show the robot's plan.
// Every page also works without it (the forms post to the server, which checks everything again).
// Text from the server is only ever put into the page as text (textContent), never as HTML.
"use strict";

(function () {
  const status = document.getElementById("save-status");

  function say(text, isProblem) {
    if (!status) return;
    status.textContent = text;
    status.classList.toggle("problem", Boolean(isProblem));
  }

  function debounce(action, milliseconds) {
    let timer = null;
    return function () {
      clearTimeout(timer);
      timer = setTimeout(action, milliseconds);
    };
  }

  async function postJson(url, body) {
    const response = await fetch(url, {
      method: "POST",
      headers: { "Content-Type": "application/json", Accept: "application/json" },
      body: JSON.stringify(body),
      credentials: "same-origin",
    });
    let data = null;
    try {
      data = await response.json();
    } catch (error) {
      data = null;
    }
    if (!response.ok) {
      const message = data && data.error ? data.error.message : "The server answered " + response.status + ".";
      const failure = new Error(message);
      failure.status = response.status;
      failure.data = data;
      throw failure;
    }
    return data;
  }

  function savedAt(isoTime) {
    const when = isoTime ? new Date(isoTime) : new Date();
    return "Saved at " + when.toLocaleTimeString([], { hour: "2-digit", minute: "2-digit", second: "2-digit" }) + ".";
  }

  const main = document.getElementById("main");
  const code = main ? main.dataset.code : null;

  // -- saving drafts -----------------------------------------------------------------------------------

  function draftOf(form) {
    const kind = form.dataset.autosave;
    if (kind === "step1") {
      const functions = {};
      form.querySelectorAll("textarea[data-part]").forEach(function (box) {
        functions[box.dataset.part] = box.value;
      });
      return { step: "step1", object: form.dataset.object, functions: functions };
    }
    if (kind === "step3") {
      const mapping = {};
      form.querySelectorAll("[data-part]").forEach(function (item) {
        const part = item.dataset.part;
        const chosen = Array.from(item.querySelectorAll('input[type="checkbox"]:checked')).map(function (box) {
          return box.value;
        });
        const added = item.querySelector("textarea");
        mapping[part] = { chosen: chosen, added: added ? added.value : "" };
      });
      return { step: "step3", object: form.dataset.object, mapping: mapping };
    }
    const answers = {};
    form.querySelectorAll('input[type="radio"]:checked').forEach(function (box) {
      answers[box.name.replace(/^answer:/, "")] = box.value;
    });
    return { step: "tutorial", answers: answers };
  }

  function autosave(form) {
    const url = "/p/" + code + "/draft";
    let retry = 1000;
    let pending = false;

    async function save() {
      pending = false;
      say("Saving…");
      try {
        const data = await postJson(url, draftOf(form));
        retry = 1000;
        say(savedAt(data.saved_at));
      } catch (error) {
        if (error.status && error.status < 500 && error.status !== 429) {
          say("Not saved: " + error.message, true);
          return;
        }
        pending = true;
        say("Not saved yet (no connection?): trying again…", true);
        setTimeout(save, retry);
        retry = Math.min(retry * 2, 30000);
      }
    }

    const later = debounce(save, 600);
    const changed = function (event) {
      if (event.target.matches("[data-check-url]")) return; // the rule box saves itself as it is checked
      pending = true;
      say("Changes not saved yet…");
      later();
    };
    form.addEventListener("input", changed);
    form.addEventListener("change", changed);
    form.addEventListener("submit", function () {
      pending = false; // the form itself carries the work to the server
    });
    window.addEventListener("pagehide", function () {
      if (pending && navigator.sendBeacon) {
        navigator.sendBeacon(url, new Blob([JSON.stringify(draftOf(form))], { type: "application/json" }));
      }
    });
  }

  document.querySelectorAll("form[data-autosave]").forEach(autosave);

  // -- checking rules as they are typed --------------------------------------------------------------

  function showProblems(container, report) {
    container.textContent = "";
    const items = report.errors.concat(report.warnings);
    container.classList.toggle("ok", report.valid && items.length === 0);
    if (!items.length) return;
    const list = document.createElement("ul");
    items.forEach(function (item) {
      const entry = document.createElement("li");
      entry.className = item.severity;
      const head = document.createElement("strong");
      let where = "";
      if (item.line) where = " (line " + item.line + ")";
      head.textContent = (item.severity === "error" ? "Problem" : "Note") + where + ": ";
      entry.appendChild(head);
      entry.appendChild(document.createTextNode(item.message + " "));
      if (item.hint) {
        const hint = document.createElement("span");
        hint.className = "hint";
        hint.textContent = item.hint;
        entry.appendChild(hint);
      }
      const codeName = document.createElement("code");
      codeName.className = "code";
      codeName.textContent = item.code;
      entry.appendChild(codeName);
      list.appendChild(entry);
    });
    container.appendChild(list);
  }

  function setSubmittable(valid) {
    document.querySelectorAll("[data-needs-valid]").forEach(function (button) {
      button.disabled = !valid;
      button.setAttribute("aria-disabled", valid ? "false" : "true");
    });
    const note = document.getElementById("submit-note");
    if (note) note.hidden = valid;
  }

  const rules = document.querySelector("textarea[data-check-url]");
  if (rules) {
    const problems = document.getElementById("problems");
    const graph = document.getElementById("graph");
    const practice = rules.dataset.practice === "true";
    let sent = 0;
    let shown = 0;

    async function check() {
      const number = ++sent;
      const text = rules.value;
      say("Checking…");
      try {
        const report = await postJson(rules.dataset.checkUrl, { rules: text, practice: practice });
        if (number < shown) return; // an older answer arriving late
        shown = number;
        showProblems(problems, report);
        setSubmittable(report.valid);
        if (graph) {
          if (report.graph_url) {
            if (graph.getAttribute("src") !== report.graph_url) graph.src = report.graph_url;
            graph.hidden = false;
            const link = document.getElementById("graph-link");
            if (link) link.href = report.graph_url;
          } else {
            graph.hidden = true;
          }
        }
        // Typed on while this was checked: that text is saved by the next check, not this one.
        say(rules.value === text ? savedAt(report.saved_at) : "Changes not saved yet…");
      } catch (error) {
        say("Not checked or saved: " + error.message, true);
      }
    }

    const later = debounce(check, 350);
    rules.addEventListener("input", function () {
      say("Changes not saved yet…");
      later();
    });
    check();

    document.querySelectorAll("button[data-insert]").forEach(function (button) {
      button.addEventListener("click", function () {
        const text = button.dataset.insert;
        const start = rules.selectionStart;
        const end = rules.selectionEnd;
        rules.value = rules.value.slice(0, start) + text + rules.value.slice(end);
        rules.focus();
        rules.selectionStart = rules.selectionEnd = start + text.length;
        rules.dispatchEvent(new Event("input"));
      });
    });
  }

  // -- the robot's plan ----------------------------------------------------------------------------------

  // The plan's steps show at once; its picture (the simulator's, maybe still being drawn) comes
  // on its own, with a progress bar until it has arrived.
  function planPicture(plan) {
    const frame = document.createElement("figure");
    frame.className = "plan-picture-frame";
    const waiting = document.createElement("p");
    waiting.className = "small picture-waiting";
    waiting.setAttribute("role", "status");
    const bar = document.createElement("progress");
    bar.setAttribute("aria-label", "Drawing the picture");
    waiting.appendChild(bar);
    waiting.appendChild(document.createTextNode(" The simulator is drawing the " + plan.name + "…"));
    frame.appendChild(waiting);
    const picture = document.createElement("img");
    picture.alt = "The " + plan.name + " after the robot's plan, in the simulator";
    picture.width = 480;
    picture.height = 360;
    picture.hidden = true;
    picture.addEventListener("load", function () {
      waiting.remove();
      picture.hidden = false;
    });
    picture.addEventListener("error", function () {
      waiting.textContent = "The picture could not be drawn now; the steps above are the robot's plan.";
    });
    frame.appendChild(picture);
    picture.src = plan.picture_url;
    return frame;
  }

  // "Watch the robot": the robot's run (its motor commands and the parts' tracks) is played at once
  // in 3D (robot_player.js). "Make a film" still has the MP4 made in a worker (tens of seconds);
  // the page asks how far it is every second, shows the frames filmed, then offers it to download.
  const FILM_POLL_MS = 1000;

  function filmProgressText(status) {
    const seconds = Math.round(status.seconds) + " s";
    if (!status.expected_frames) return "The robot is getting ready… (" + seconds + ")";
    return "Filming the robot: " + status.frames + " of " + status.expected_frames + " frames (" + seconds + ")";
  }

  function watchRobot(plan, filmUrl) {
    const frame = document.createElement("div");
    frame.className = "robot-film";
    const watch = document.createElement("button");
    watch.type = "button";
    watch.className = "watch-robot";
    watch.textContent = "Watch the robot";
    frame.appendChild(watch);
    const stage = document.createElement("div");
    stage.className = "robot-player";
    const stageNote = document.createElement("p");
    stageNote.className = "small";
    stageNote.setAttribute("role", "status");
    stage.appendChild(stageNote);
    frame.appendChild(stage);
    const button = document.createElement("button");
    button.type = "button";
    button.className = "film-robot";
    button.textContent = "Make a film to download (MP4)";
    frame.appendChild(button);
    const progress = document.createElement("p");
    progress.className = "small film-progress";
    progress.setAttribute("role", "status");
    progress.hidden = true;
    const bar = document.createElement("progress");
    bar.setAttribute("aria-label", "Filming the robot");
    const words = document.createElement("span");
    progress.appendChild(bar);
    progress.appendChild(document.createTextNode(" "));
    progress.appendChild(words);
    frame.appendChild(progress);

    function show(status) {
      if (status.expected_frames) {
        bar.max = status.expected_frames;
        bar.value = status.frames;
      } else {
        bar.removeAttribute("value");
      }
      words.textContent = filmProgressText(status);
    }

    function whyNot(outcome) {
      if (!outcome || outcome.carried_out || !outcome.reason) return;
      const note = document.createElement("p");
      note.className = "feedback";
      note.textContent = outcome.reason.message;
      frame.appendChild(note);
    }

    function play(status) {
      progress.hidden = true;
      const link = document.createElement("a");
      link.className = "film-download";
      link.href = status.video_url;
      link.download = plan.object + ".mp4";
      link.textContent = "Download the film (MP4, " + Math.max(1, Math.round(status.bytes / 1024)) + " kB)";
      frame.appendChild(link);
      button.remove();
    }

    watch.addEventListener("click", async function () {
      watch.disabled = true;
      stageNote.textContent = "The robot is working out its motions…";
      try {
        const [player, run] = await Promise.all([
          import("/web/static/robot_player.js").then(function (module) {
            module.loadPanda(); // the arm's meshes load while the robot works out its motions
            return module;
          }),
          postJson(filmUrl + "/playback", { object: plan.object, fits: plan.fits }),
        ]);
        await player.createPlayer(stage, run);
        stageNote.remove();
        watch.remove();
        whyNot(run.outcome);
      } catch (error) {
        stageNote.textContent = "The robot cannot be shown now: " + error.message;
        watch.disabled = false;
      }
    });

    async function follow(status) {
      while (status.state === "filming") {
        show(status);
        await new Promise(function (resolve) { setTimeout(resolve, FILM_POLL_MS); });
        const response = await fetch(status.status_url, { headers: { Accept: "application/json" }, credentials: "same-origin" });
        if (!response.ok) throw new Error("The server answered " + response.status + ".");
        status = await response.json();
      }
      if (status.state === "ready") {
        play(status);
      } else {
        throw new Error(status.error ? status.error.message : "The film could not be made.");
      }
    }

    button.addEventListener("click", async function () {
      button.disabled = true;
      progress.hidden = false;
      words.textContent = "Asking for the film…";
      try {
        await follow(await postJson(filmUrl, { object: plan.object, fits: plan.fits }));
      } catch (error) {
        words.textContent = "No film now: " + error.message;
        bar.remove();
        button.disabled = false;
      }
    });
    return frame;
  }

  // -- "Why?" beside each step, and a "Why not…?" box: the robot explains its plan -------------------

  function explainUrl() {
    return document.getElementById("show-plan").dataset.planUrl.replace(/\/plan$/, "/explain");
  }

  function answerBox(className) {
    const box = document.createElement("p");
    box.className = "explanation " + className;
    box.setAttribute("aria-live", "polite");
    return box;
  }

  function whyButton(plan, number) {
    const wrapper = document.createElement("span");
    const button = document.createElement("button");
    button.type = "button";
    button.className = "why";
    button.textContent = "Why?";
    const answer = answerBox("why-answer");
    button.addEventListener("click", async function () {
      button.disabled = true;
      answer.textContent = "The robot is thinking…";
      try {
        answer.textContent = (await postJson(explainUrl(), { object: plan.object, why: String(number) })).answer;
      } catch (error) {
        answer.textContent = error.message;
      } finally {
        button.disabled = false;
      }
    });
    wrapper.appendChild(button);
    wrapper.appendChild(answer);
    return wrapper;
  }

  function whyNotBox(plan) {
    const form = document.createElement("form");
    form.className = "why-not";
    const label = document.createElement("label");
    label.textContent = "Why not… ";
    const input = document.createElement("input");
    input.name = "why_not";
    input.placeholder = "leave out step 2 · shade before light bulb · attach shade";
    input.maxLength = 200;
    label.appendChild(input);
    const button = document.createElement("button");
    button.type = "submit";
    button.textContent = "Ask the robot";
    const answer = answerBox("why-not-answer");
    const alternative = document.createElement("ol");
    alternative.className = "why-not-plan";
    form.append(label, button, answer, alternative);
    form.addEventListener("submit", async function (event) {
      event.preventDefault();
      event.stopPropagation();
      button.disabled = true;
      answer.textContent = "The robot is planning again…";
      alternative.textContent = "";
      try {
        const data = await postJson(explainUrl(), { object: plan.object, why_not: input.value });
        answer.textContent = data.answer;
        data.alternative.forEach(function (step) {
          const item = document.createElement("li");
          item.textContent = step;
          alternative.appendChild(item);
        });
      } catch (error) {
        answer.textContent = error.message;
      } finally {
        button.disabled = false;
      }
    });
    return form;
  }

  const planButton = document.getElementById("show-plan");
  if (planButton && rules) {
    const section = document.getElementById("plan");
    const body = document.getElementById("plan-body");
    planButton.addEventListener("click", async function () {
      planButton.disabled = true;
      section.hidden = false;
      body.textContent = "The robot is planning…";
      try {
        const data = await postJson(planButton.dataset.planUrl, { rules: rules.value });
        body.textContent = "";
        data.plans.forEach(function (plan) {
          const block = document.createElement("div");
          block.className = "plan-object";
          const title = document.createElement("h3");
          title.textContent = "The " + plan.name;
          block.appendChild(title);
          if (plan.steps.length) {
            const list = document.createElement("ol");
            plan.steps.forEach(function (step, index) {
              const item = document.createElement("li");
              item.textContent = step + " ";
              item.appendChild(whyButton(plan, index + 1));
              list.appendChild(item);
            });
            block.appendChild(list);
            block.appendChild(whyNotBox(plan));
          } else {
            const none = document.createElement("p");
            none.textContent = plan.status === "solved"
              ? "Nothing to assemble: your rules are satisfied as the object stands."
              : "The robot found no plan (" + plan.status + "). " + plan.message;
            block.appendChild(none);
          }
          if (plan.steps.length && !plan.works && plan.message) {
            const warning = document.createElement("p");
            warning.className = "feedback";
            warning.textContent = plan.message;
            block.appendChild(warning);
          }
          if (plan.picture_url) block.appendChild(planPicture(plan));
          if (planButton.dataset.filmUrl && plan.fits.length && plan.fits.every(Boolean)) {
            block.appendChild(watchRobot(plan, planButton.dataset.filmUrl));
          }
          body.appendChild(block);
        });
        const advice = document.createElement("p");
        advice.className = "small";
        advice.textContent = "Not what you expected? Change your rules (or your functions in step 1) and look again.";
        body.appendChild(advice);
      } catch (error) {
        body.textContent = "No plan: " + error.message;
      } finally {
        planButton.disabled = false;
      }
    });
  }

  // -- forms: one submission at a time ----------------------------------------------------------------

  document.querySelectorAll("form").forEach(function (form) {
    form.addEventListener("submit", function (event) {
      if (form.dataset.sending === "true") {
        event.preventDefault();
        return;
      }
      form.dataset.sending = "true";
      const button = form.querySelector('button[type="submit"]');
      if (button && form.id === "step3-form") button.textContent = "The robot is trying your model…";
    });
  });
})();
