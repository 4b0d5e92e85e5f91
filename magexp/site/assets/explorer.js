// The claims explorer of the results website (magexp.site): draws each <div class="mx-explorer"
// data-table="claims|numbers"> from the JSON the page embeds (<script id="mx-data">), with a menu per
// filter (its options derived from the data by magexp.site.data), sorting by the columns it names, and
// each row opening its full record, its figure and the CSVs it read. Plain JS, no server, no network.
(function () {
  "use strict";

  // the columns each table shows in its rows; every other field is in the opened row
  var SHOWN = {
    claims: ["paper", "role", "verdict", "reading", "id", "text", "p", "p_adjusted"],
    numbers: ["paper", "artifact", "label", "paper_value", "judged_value", "judged_lo", "judged_hi", "verdict",
              "rel_difference"]
  };
  // the fields the opened row lists, in order (empty ones left out)
  var DETAIL = {
    claims: ["text", "section", "by", "artifact", "family", "reason", "evidence", "level", "p", "p_adjusted",
             "p_min", "detectable", "observed", "seeds", "effect", "seeds_planned", "primary_reading", "why",
             "robustness", "readings_total", "readings_holding"],
    numbers: ["label", "quantity", "estimator", "setting", "truth", "paper_value", "value", "q25", "q75", "n_seeds",
              "tolerance", "lo", "hi", "success_rate", "truth_in_interval", "reason", "judged_runs", "judged_n",
              "judged_value", "judged_lo", "judged_hi", "scale", "rel_difference"]
  };

  function el(tag, attrs, text) {
    var node = document.createElement(tag);
    Object.keys(attrs || {}).forEach(function (k) { node.setAttribute(k, attrs[k]); });
    if (text !== undefined && text !== null) { node.textContent = String(text); }
    return node;
  }

  // the site's root (where results/ sits), from this script's own address: links work from file:// too
  var SOURCE = document.currentScript ? document.currentScript.src : "";
  function siteRoot() {
    return SOURCE.replace(/results\/assets\/explorer\.js[^\/]*$/, "");
  }

  function shown(value) {
    if (value === null || value === undefined) { return ""; }
    if (typeof value === "number") { return Number(value.toPrecision(4)).toString(); }
    return String(value);
  }

  function detail(row, kind, root) {
    var box = el("div", {"class": "mx-detail"});
    var list = el("dl");
    DETAIL[kind].forEach(function (key) {
      if (row[key] === "" || row[key] === null || row[key] === undefined) { return; }
      list.appendChild(el("dt", {}, key));
      list.appendChild(el("dd", {}, shown(row[key])));
    });
    box.appendChild(list);
    if (row.files && row.files.length) {
      var files = el("p", {}, "Runs it read: ");
      row.files.forEach(function (name, k) {
        if (k) { files.appendChild(document.createTextNode(", ")); }
        files.appendChild(el("a", {"href": root + "results/" + name}, name));
      });
      box.appendChild(files);
    }
    if (row.png) {
      var link = el("a", {"href": root + "results/" + row.png});
      link.appendChild(el("img", {"src": root + "results/" + row.png, "alt": row.png}));
      box.appendChild(link);
    }
    return box;
  }

  function Explorer(node, table, kind, root) {
    this.node = node; this.table = table; this.kind = kind; this.root = root;
    this.chosen = {}; this.sort = null; this.descending = false;
    this.build();
  }

  Explorer.prototype.build = function () {
    var self = this, bar = el("div", {"class": "mx-filters"});
    Object.keys(this.table.filters).forEach(function (key) {
      var label = el("label", {}, key + " "), menu = el("select", {"data-filter": key});
      menu.appendChild(el("option", {"value": ""}, "all"));
      self.table.filters[key].forEach(function (value) {
        menu.appendChild(el("option", {"value": value}, value || "(none)"));
      });
      menu.addEventListener("change", function () { self.chosen[key] = menu.value; self.draw(); });
      label.appendChild(menu);
      bar.appendChild(label);
    });
    this.count = el("span", {"class": "mx-count"});
    bar.appendChild(this.count);
    this.node.appendChild(bar);
    var wrap = el("div", {"class": "mx-wrap"}), grid = el("table", {"class": "mx-table"}), head = el("tr");
    SHOWN[this.kind].forEach(function (key) {
      var sortable = self.table.sorts.indexOf(key) >= 0;
      var th = el("th", sortable ? {"class": "mx-sortable", "data-sort": key, "title": "sort"} : {},
                  key + (sortable ? " ↕" : ""));
      if (sortable) {
        th.addEventListener("click", function () {
          self.descending = self.sort === key ? !self.descending : false;
          self.sort = key;
          self.draw();
        });
      }
      head.appendChild(th);
    });
    var thead = el("thead");
    thead.appendChild(head);
    grid.appendChild(thead);
    this.body = el("tbody");
    grid.appendChild(this.body);
    wrap.appendChild(grid);
    this.node.appendChild(wrap);
    this.draw();
  };

  Explorer.prototype.rows = function () {
    var self = this;
    var rows = this.table.rows.filter(function (row) {
      return Object.keys(self.chosen).every(function (key) {
        if (!self.chosen[key]) { return true; }
        var multi = self.table.multi.indexOf(key) >= 0;  // several values in one field (magexp.site.data.MULTI)
        var values = multi ? String(row[key]).split(self.table.separator) : [String(row[key])];
        return values.indexOf(self.chosen[key]) >= 0;
      });
    });
    if (this.sort) {
      var key = this.sort, sign = this.descending ? -1 : 1;
      rows = rows.slice().sort(function (a, b) {  // rows without a value last, whichever the direction
        if (a[key] === null) { return b[key] === null ? 0 : 1; }
        if (b[key] === null) { return -1; }
        return sign * (a[key] - b[key]);
      });
    }
    return rows;
  };

  Explorer.prototype.draw = function () {
    var self = this, rows = this.rows();
    this.body.textContent = "";
    this.count.textContent = rows.length + " of " + this.table.rows.length + " rows";
    rows.forEach(function (row) {
      var tr = el("tr", {"class": "mx-row", "tabindex": "0"});
      SHOWN[self.kind].forEach(function (key) { tr.appendChild(el("td", {"data-key": key}, shown(row[key]))); });
      tr.addEventListener("click", function () { self.toggle(tr, row); });
      tr.addEventListener("keydown", function (e) { if (e.key === "Enter") { self.toggle(tr, row); } });
      self.body.appendChild(tr);
    });
  };

  Explorer.prototype.toggle = function (tr, row) {
    var next = tr.nextSibling;
    if (next && next.classList.contains("mx-open")) { next.remove(); return; }
    var open = el("tr", {"class": "mx-open"}), td = el("td", {"colspan": String(SHOWN[this.kind].length)});
    td.appendChild(detail(row, this.kind, this.root));
    open.appendChild(td);
    tr.parentNode.insertBefore(open, next);
  };

  function start() {
    var source = document.getElementById("mx-data");
    if (!source) { return; }
    var data = JSON.parse(source.textContent), root = siteRoot();
    document.querySelectorAll(".mx-explorer").forEach(function (node) {
      var kind = node.getAttribute("data-table");
      node.explorer = new Explorer(node, data[kind], kind, root);
    });
  }

  if (document.readyState === "loading") { document.addEventListener("DOMContentLoaded", start); } else { start(); }
}());
