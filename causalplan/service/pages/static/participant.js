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

  // -- saving: nothing typed is lost -------------------------------------------------------------------

  // Each box (or group of boxes saved together) is a draft with a key and a revision that only
  // grows. A change goes at once into this tab's outbox (sessionStorage) and to the server within
  // SAVE_DELAY_MS, and again with a keepalive request when the page is hidden or left. The outbox
  // entry goes only when the server acknowledges that revision; a page that finds an entry newer
  // than the server's text (a reload or Back before the save arrived) puts it back and sends it.
  // The server keeps the newest revision, so a late or repeated request never undoes newer text.
  const SAVE_DELAY_MS = 300;
  const drafts = [];
  const arrival = performance.getEntriesByType ? performance.getEntriesByType("navigation")[0] : null;
  const restoresForms = !arrival || arrival.type === "reload" || arrival.type === "back_forward";

  function outboxName(key) {
    return "causalplan:" + code + ":" + key;
  }

  function readOutbox(key) {
    try {
      return JSON.parse(sessionStorage.getItem(outboxName(key)));
    } catch (error) {
      return null;
    }
  }

  function writeOutbox(key, entry) {
    try {
      sessionStorage.setItem(outboxName(key), JSON.stringify(entry));
    } catch (error) {
      // storage full or refused: the save requests still carry the text
    }
  }

  // Once the page is being left (a reload, a link, Back), an answer that arrives must not clear
  // the outbox: the next page may already have been made from what the server had before that
  // save, and only the outbox can then put the text back. Typing again means the participant
  // stayed (a cancelled leave).
  let leaving = false;
  window.addEventListener("beforeunload", function () { leaving = true; });

  function clearOutbox(key, revision) {
    if (leaving) return;
    const entry = readOutbox(key);
    if (entry && entry.revision <= revision) sessionStorage.removeItem(outboxName(key));
  }

  // Forms posted by the browser carry the page's newest revision, so a form older than what
  // the server has stored (posted again from an old page) changes nothing.
  function stampForms() {
    const newest = drafts.reduce(function (most, draft) { return Math.max(most, draft.revision); }, 0);
    document.querySelectorAll('input[type="hidden"][name="revision"]').forEach(function (field) {
      field.value = String(newest);
    });
  }

  // options: key, stored (the server's revision of the text in the page), snapshot(), restore(snapshot
  // or null for the text the server sent), send(snapshot, revision, keepalive) -> Promise of the answer.
  function makeDraft(options) {
    const draft = { key: options.key, revision: options.stored, send: options.send };
    let timer = null;
    let retry = 1000;

    draft.changed = function () {
      leaving = false;
      draft.revision = Math.max(Date.now(), draft.revision + 1);
      writeOutbox(draft.key, { revision: draft.revision, snapshot: options.snapshot() });
      stampForms();
      say("Changes not saved yet…");
      clearTimeout(timer);
      timer = setTimeout(draft.save, SAVE_DELAY_MS);
    };

    draft.save = async function () {
      clearTimeout(timer);
      const entry = readOutbox(draft.key);
      if (!entry) return;
      say("Saving…");
      try {
        const data = await options.send(entry.snapshot, entry.revision, false);
        retry = 1000;
        clearOutbox(draft.key, entry.revision);
        if (data && data.revision > draft.revision) draft.revision = data.revision;
        if (!readOutbox(draft.key)) say(savedAt(data && data.saved_at)); // nothing newer typed meanwhile
      } catch (error) {
        if (error.status && error.status < 500 && error.status !== 429) {
          clearOutbox(draft.key, entry.revision); // refused (a closed step): sending it again cannot help
          say("Not saved: " + error.message, true);
          return;
        }
        say("Not saved yet (no connection?): trying again…", true);
        timer = setTimeout(draft.save, retry);
        retry = Math.min(retry * 2, 30000);
      }
    };

    // The page is hidden or going away: send what the server has not acknowledged, in a request
    // that outlives the page. The outbox keeps it until an answer says it arrived.
    draft.flush = function () {
      const entry = readOutbox(draft.key);
      if (!entry) return;
      clearTimeout(timer);
      options.send(entry.snapshot, entry.revision, true).then(
        function () { clearOutbox(draft.key, entry.revision); },
        function () { /* the next page sends it again */ }
      );
    };

    // On arrival the boxes hold the server's text, not what the browser restored from its cache
    // on a reload or Back/Forward, unless this tab typed something newer that may not have reached
    // the server. On a plain visit the browser restores nothing: text already in a box was typed
    // before this script ran, and is a change like any other.
    const typed = JSON.stringify(options.snapshot());
    options.restore(null);
    const waiting = readOutbox(draft.key);
    drafts.push(draft);
    if (waiting && waiting.revision > options.stored) {
      options.restore(waiting.snapshot);
      draft.revision = waiting.revision;
      setTimeout(draft.save, 0);
    } else {
      if (waiting) sessionStorage.removeItem(outboxName(draft.key));
      if (!restoresForms && typed !== JSON.stringify(options.snapshot())) {
        options.restore(JSON.parse(typed));
        draft.changed();
      }
    }
    stampForms();
    return draft;
  }

  window.addEventListener("pagehide", function () {
    drafts.forEach(function (draft) { draft.flush(); });
  });
  document.addEventListener("visibilitychange", function () {
    if (document.visibilityState === "hidden") drafts.forEach(function (draft) { draft.flush(); });
  });
  window.addEventListener("pageshow", function (event) {
    if (event.persisted && drafts.length) window.location.reload(); // from the back-forward cache: ask the server
  });

  function sendJson(url, body, keepalive) {
    if (!keepalive) return postJson(url, body);
    return fetch(url, {
      method: "POST",
      headers: { "Content-Type": "application/json", Accept: "application/json" },
      body: JSON.stringify(body),
      credentials: "same-origin",
      keepalive: true,
    }).then(function (response) {
      if (!response.ok) throw new Error("The server answered " + response.status + ".");
      return response.json();
    });
  }

  function snapshotOf(form) {
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

  // Put a snapshot back into the form's boxes (null: the text the server sent with the page).
  function restoreForm(form, snapshot) {
    const kind = form.dataset.autosave;
    form.querySelectorAll("textarea:not([data-check-url])").forEach(function (box) {
      box.value = box.defaultValue;
    });
    form.querySelectorAll('input[type="checkbox"], input[type="radio"]').forEach(function (box) {
      box.checked = box.defaultChecked;
    });
    if (!snapshot) return;
    if (kind === "step1") {
      form.querySelectorAll("textarea[data-part]").forEach(function (box) {
        if (box.dataset.part in snapshot.functions) box.value = snapshot.functions[box.dataset.part];
      });
    } else if (kind === "step3") {
      form.querySelectorAll("[data-part]").forEach(function (item) {
        const entry = snapshot.mapping[item.dataset.part];
        if (!entry) return;
        item.querySelectorAll('input[type="checkbox"]').forEach(function (box) {
          box.checked = entry.chosen.indexOf(box.value) >= 0;
        });
        const added = item.querySelector("textarea");
        if (added) added.value = entry.added;
      });
    } else {
      form.querySelectorAll('input[type="radio"]').forEach(function (box) {
        box.checked = snapshot.answers[box.name.replace(/^answer:/, "")] === box.value;
      });
    }
  }

  function autosave(form) {
    const url = "/p/" + code + "/draft";
    const draft = makeDraft({
      key: form.dataset.draftKey,
      stored: Number(form.dataset.revision || 0),
      snapshot: function () { return snapshotOf(form); },
      restore: function (snapshot) { restoreForm(form, snapshot); },
      send: function (snapshot, revision, keepalive) {
        return sendJson(url, Object.assign({}, snapshot, { revision: revision }), keepalive);
      },
    });
    const changed = function (event) {
      if (event.target.matches("[data-check-url]")) return; // the rule box is a draft of its own
      draft.changed();
    };
    form.addEventListener("input", changed);
    form.addEventListener("change", changed);
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
  let rulesDraft = null;
  let onChecked = null; // step 2's status hears of each check
  if (rules) {
    const problems = document.getElementById("problems");
    const graph = document.getElementById("graph");
    const practice = rules.dataset.practice === "true";
    let sent = 0;
    let shown = 0;

    function showCheck(report) {
      showProblems(problems, report);
      setSubmittable(report.valid);
      if (typeof onChecked === "function") onChecked(report);
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
    }

    // The rule box is saved by checking it: the check's answer says what is wrong and that it is saved.
    async function check(text, revision, keepalive) {
      const body = { rules: text, practice: practice, revision: revision };
      if (keepalive) return sendJson(rules.dataset.checkUrl, body, true);
      const number = ++sent;
      const report = await postJson(rules.dataset.checkUrl, body);
      if (number > shown && rules.value === text) {
        shown = number; // an older answer arriving late is not shown
        showCheck(report);
      }
      return report;
    }

    rulesDraft = makeDraft({
      key: rules.dataset.draftKey,
      stored: Number(rules.dataset.revision || 0),
      snapshot: function () { return rules.value; },
      restore: function (snapshot) { rules.value = snapshot === null ? rules.defaultValue : snapshot; },
      send: check,
    });
    rules.addEventListener("input", function () { rulesDraft.changed(); });
    if (!rules.value.trim()) {
      setSubmittable(false); // nothing to check yet, and nothing to point out before anything is typed
    } else if (!readOutbox(rulesDraft.key)) {
      check(rules.value, rulesDraft.revision, false).catch(function (error) {
        say("Not checked: " + error.message, true);
      });
    }

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

  // The player's code and the arm's meshes load while the participant reads the plan (the server
  // computes the robot's run meanwhile too), so "Watch the robot" starts moving at once.
  let playerModule = null;

  function loadPlayer() {
    if (!playerModule) {
      playerModule = import("/web/static/robot_player.js").then(function (module) {
        module.loadPanda().catch(function () { /* tried again on the click */ });
        return module;
      });
      playerModule.catch(function () { playerModule = null; });
    }
    return playerModule;
  }

  function watchRobot(plan, filmUrl) {
    loadPlayer().catch(function () { /* the click says why */ });
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
          loadPlayer(),
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

  // -- step 2's one status, and the plan on screen never stale -----------------------------------------

  // One sentence says whether the rules can be submitted and whether the robot's plan works.
  // The plan, its picture and the robot's answers belong to the rules they were made for: once
  // the rule box says something else, they are marked out of date and their questions closed.
  const modelStatus = document.getElementById("model-status");
  const planSection = document.getElementById("plan");
  const step2 = { valid: modelStatus ? modelStatus.dataset.valid === "true" : false, plan: null };

  function planIsCurrent() {
    return Boolean(step2.plan) && rules !== null && rules.value === step2.plan.rules;
  }

  function showStatus() {
    if (!modelStatus || !rules) return;
    const goal = modelStatus.dataset.goal;
    const objects = modelStatus.dataset.objects;
    let text = "";
    let tone = "neutral";
    if (!rules.value.trim()) {
      text = "Write your rules: they are checked as you type.";
    } else if (!step2.valid) {
      text = "Not ready to submit yet: fix the problem shown under your rules.";
      tone = "problem";
    } else if (!step2.plan || step2.plan.failed) {
      text = "Ready to submit: your rules have no problems. Show the robot's plan to see whether they make " +
        objects + " produce " + goal + ".";
    } else if (!planIsCurrent()) {
      text = "Ready to submit. Your rules changed after the robot's plan: show the plan again to see whether they work.";
    } else if (!step2.plan.failures.length) {
      text = "Ready to submit: your rules have no problems, and the robot's plan makes " + objects + " produce " +
        goal + ".";
      tone = "good";
    } else {
      text = "You can submit, but following your rules the robot would not make the real " +
        step2.plan.failures.join(" or the real ") + " produce " + goal +
        ": something in how it works is missing. Change your rules, or submit them as they are.";
      tone = "warning";
    }
    modelStatus.textContent = text;
    modelStatus.dataset.tone = tone;
  }

  function markPlan() {
    if (!planSection || !step2.plan) return;
    const stale = !planIsCurrent();
    planSection.classList.toggle("stale", stale);
    const notice = document.getElementById("plan-stale");
    if (notice) notice.hidden = !stale;
    planSection.querySelectorAll("#plan-body button, #plan-body input").forEach(function (control) {
      if (stale) {
        control.dataset.wasDisabled = control.disabled ? "true" : "false";
        control.disabled = true;
      } else if (control.dataset.wasDisabled) {
        control.disabled = control.dataset.wasDisabled === "true";
        delete control.dataset.wasDisabled;
      }
    });
    if (stale) {
      planSection.querySelectorAll(".explanation, .why-not-plan, .why-not-suggestions").forEach(function (box) {
        box.textContent = "";
      });
    }
  }

  if (rules) {
    rules.addEventListener("input", function () {
      showStatus();
      markPlan();
    });
    onChecked = function (report) {
      step2.valid = report.valid;
      showStatus();
    };
    showStatus();
  }

  // -- "Why?" beside each step, and a "Why not…?" box: the robot explains the plan on screen ----------

  function explainUrl() {
    return document.getElementById("show-plan").dataset.planUrl.replace(/\/plan$/, "/explain");
  }

  function answerBox(className) {
    const box = document.createElement("p");
    box.className = "explanation " + className;
    box.setAttribute("aria-live", "polite");
    return box;
  }

  // Ask about the plan on screen (its rules go with the question); an answer arriving after the
  // rules changed is not shown.
  async function ask(question) {
    const asked = step2.plan ? step2.plan.rules : rules.value;
    const data = await postJson(explainUrl(), Object.assign({ rules: asked }, question));
    if (!step2.plan || step2.plan.rules !== asked || !planIsCurrent()) return null;
    return data;
  }

  function whyButton(plan, number) {
    const wrapper = document.createElement("span");
    const button = document.createElement("button");
    button.type = "button";
    button.className = "why";
    button.textContent = "Why?";
    button.setAttribute("aria-label", "Why step " + number + "?");
    const answer = answerBox("why-answer");
    button.addEventListener("click", async function () {
      button.disabled = true;
      answer.textContent = "The robot is thinking…";
      try {
        const data = await ask({ object: plan.object, why: String(number) });
        answer.textContent = data ? data.answer : "";
      } catch (error) {
        answer.textContent = planIsCurrent() ? error.message : "";
      } finally {
        button.disabled = !planIsCurrent();
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
    label.textContent = "Ask the robot about the " + plan.name + ": ";
    const input = document.createElement("input");
    input.name = "why_not";
    input.type = "text";
    input.placeholder = (plan.questions || []).slice(0, 2).join(" · ");
    input.maxLength = 200;
    label.appendChild(input);
    const button = document.createElement("button");
    button.type = "submit";
    button.textContent = "Ask the robot";
    const examples = document.createElement("p");
    examples.className = "small why-not-examples";
    if (plan.questions && plan.questions.length) examples.textContent = "For example: " + plan.questions.join(" · ");
    const answer = answerBox("why-not-answer");
    const suggestions = document.createElement("div");
    suggestions.className = "why-not-suggestions";
    const alternative = document.createElement("ol");
    alternative.className = "why-not-plan";
    form.append(label, button, examples, answer, suggestions, alternative);

    function offer(questions) {
      suggestions.textContent = "";
      if (!questions || !questions.length) return;
      const intro = document.createElement("p");
      intro.className = "small";
      intro.textContent = "Did you mean:";
      suggestions.appendChild(intro);
      questions.forEach(function (question) {
        const choice = document.createElement("button");
        choice.type = "button";
        choice.className = "suggestion";
        choice.textContent = question;
        choice.addEventListener("click", function () {
          input.value = question;
          form.requestSubmit();
        });
        suggestions.appendChild(choice);
      });
    }

    form.addEventListener("submit", async function (event) {
      event.preventDefault();
      event.stopPropagation();
      button.disabled = true;
      answer.textContent = "The robot is planning again…";
      alternative.textContent = "";
      suggestions.textContent = "";
      try {
        const data = await ask({ object: plan.object, why_not: input.value });
        if (!data) {
          answer.textContent = "";
          return;
        }
        answer.textContent = data.answer;
        offer(data.suggestions);
        data.alternative.forEach(function (step) {
          const item = document.createElement("li");
          item.textContent = step;
          alternative.appendChild(item);
        });
      } catch (error) {
        if (!planIsCurrent()) {
          answer.textContent = "";
          return;
        }
        answer.textContent = error.message;
        const details = error.data && error.data.error ? error.data.error.details : null;
        offer(details ? details.suggestions : null);
      } finally {
        button.disabled = !planIsCurrent();
      }
    });
    return form;
  }

  const planButton = document.getElementById("show-plan");
  if (planButton && rules) {
    const body = document.getElementById("plan-body");
    planButton.addEventListener("click", async function () {
      const asked = rules.value;
      planButton.disabled = true;
      planSection.hidden = false;
      planSection.classList.remove("stale");
      const notice = document.getElementById("plan-stale");
      if (notice) notice.hidden = true;
      step2.plan = null; // the old plan goes until the new one arrives
      showStatus();
      body.textContent = "The robot is planning…";
      try {
        const data = await postJson(planButton.dataset.planUrl, { rules: asked, revision: rulesDraft.revision });
        body.textContent = "";
        step2.plan = {
          rules: asked,
          failures: data.plans.filter(function (plan) { return !plan.works; }).map(function (plan) { return plan.name; }),
        };
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
            const note = document.createElement("p");
            note.className = "plan-note";
            note.textContent = plan.message;
            block.appendChild(note);
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
        step2.plan = { rules: asked, failures: [], failed: true };
        body.textContent = "No plan: " + error.message;
      } finally {
        planButton.disabled = false;
        showStatus();
        markPlan();
      }
    });
  }

  // -- graphs: a tap (or a click) opens one full size ------------------------------------------------------

  // The drawing in the page is scaled to its column, too small to read on a phone: the button
  // around it opens a dialog with the drawing at full size, which scrolls inside the dialog.
  let graphDialog = null;

  function openGraph(image) {
    if (!graphDialog) {
      graphDialog = document.createElement("dialog");
      graphDialog.className = "graph-dialog";
      graphDialog.setAttribute("aria-label", "The graph, full size");
      const bar = document.createElement("p");
      bar.className = "actions";
      const close = document.createElement("button");
      close.type = "button";
      close.textContent = "Close";
      close.addEventListener("click", function () { graphDialog.close(); });
      bar.appendChild(close);
      const holder = document.createElement("div");
      holder.className = "graph-full";
      holder.appendChild(document.createElement("img"));
      graphDialog.append(bar, holder);
      graphDialog.addEventListener("click", function (event) {
        if (event.target === graphDialog) graphDialog.close(); // a tap beside the drawing
      });
      document.body.appendChild(graphDialog);
    }
    const big = graphDialog.querySelector("img");
    big.alt = image.alt;
    big.src = image.currentSrc || image.src;
    // Full size, but at least as wide as the dialog: a small drawing is enlarged, a large one scrolls.
    big.style.width = image.naturalWidth ? image.naturalWidth * 1.5 + "px" : "";
    graphDialog.showModal();
  }

  document.querySelectorAll("figure.graph img").forEach(function (image) {
    const zoom = document.createElement("button");
    zoom.type = "button";
    zoom.className = "graph-zoom";
    zoom.setAttribute("aria-label", "Open the graph full size");
    image.replaceWith(zoom);
    zoom.appendChild(image);
    zoom.addEventListener("click", function () {
      if (!image.hidden && image.getAttribute("src")) openGraph(image);
    });
  });

  // -- the end: back to the platform once the server has confirmed everything is stored ----------------

  const backLink = document.querySelector("a#back-to-platform[data-redirect-seconds]");
  if (backLink) {
    const arrived = Date.now();
    const note = document.getElementById("redirect-note");
    let retry = 1000;
    const leave = function () {
      const wait = Math.max(0, Number(backLink.dataset.redirectSeconds) * 1000 - (Date.now() - arrived));
      setTimeout(function () { window.location.assign(backLink.href); }, wait);
    };
    const confirmSaved = async function () {
      if (!backLink.dataset.progressUrl) {
        leave(); // nothing of theirs to store (they declined)
        return;
      }
      try {
        const response = await fetch(backLink.dataset.progressUrl, {
          headers: { Accept: "application/json" },
          credentials: "same-origin",
          cache: "no-store",
        });
        const progress = response.ok ? await response.json() : null;
        if (!progress || !progress.finished) throw new Error("not confirmed");
        Object.keys(sessionStorage).forEach(function (name) {
          if (name.indexOf(outboxName("")) === 0) sessionStorage.removeItem(name); // every draft's entry
        });
        leave();
      } catch (error) {
        if (note) note.textContent = "Making sure your answers are stored… (you can also use the button above)";
        setTimeout(confirmSaved, retry);
        retry = Math.min(retry * 2, 15000);
      }
    };
    confirmSaved();
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
