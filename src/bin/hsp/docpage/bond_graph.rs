//! The bond-graph figure of the documentation page, drawn from the model's own bond graph (its
//! elements, bonds, causal strokes and signal blocks) grouped as the paper draws it.
//!
//! Each element goes to one group by its name, as the fragments name it (`<prefix>.<stem>...`):
//! [`GROUPS`] maps the servo valve's stems to the paper's fragments BG1, BG2 and BG3 of Fig. 2b
//! (the rest of `servo_valve.*` is BG3) and every other fragment by its prefix. An element no rule
//! claims goes to the group [`OTHER`], so that nothing of the model is ever left out of the
//! picture. The signal part of Fig. 8 (reference, controller with potentiometer and amplifiers)
//! is a group of its own, drawn apart.
//!
//! Each group is laid out on its own, deterministically: its multiport elements (junctions, TF,
//! GY, fields) in columns by breadth-first distance from the group's entry, each one-port element
//! (C, I, R, sources) stacked under the element it is bonded to. The groups are placed in the
//! paper's left-to-right order, in rows that fit the page. Bonds are half arrows in the power
//! direction with the causal stroke at the end where the effort enters the element.

use std::collections::VecDeque;
use std::fmt::Write as _;

use hydraulic_slewing_plate::bond_graph::{BondGraph, ElementKind, SignalKind};

/// A group of the figure: its caption, the name prefix of its elements and, when the fragment
/// behind the prefix spans several of the paper's fragments, the stems (the name's part after
/// the prefix, up to the next `.`) it claims; empty stems claim the whole prefix.
pub struct Group {
    pub label: &'static str,
    prefix: &'static str,
    stems: &'static [&'static str],
}

/// The groups, in the paper's left-to-right order (first match wins).
pub const GROUPS: &[Group] = &[
    Group {
        label: "BG1 coil and torque motor (Fig. 2b)",
        prefix: "servo_valve",
        stems: &[
            "amplifier",
            "coil",
            "R_bob",
            "L_bob",
            "k_phi",
            "flapper",
            "m_f",
            "b_f",
        ],
    },
    Group {
        label: "BG2 flapper-nozzle and spool, supply and tank (Fig. 2b)",
        prefix: "servo_valve",
        stems: &[
            "supply",
            "supply_line",
            "tank",
            "tank_line",
            "chamber_a",
            "chamber_b",
            "C_Ha",
            "C_Hb",
            "R1",
            "R2",
            "R_nozzle_a",
            "R_nozzle_b",
            "A_s_a",
            "A_s_b",
            "spool",
            "m_v",
            "b_v",
            "spool_stop",
            "springs",
        ],
    },
    Group {
        label: "BG3 spool metering and vane motor (Fig. 2b)",
        prefix: "servo_valve",
        stems: &[],
    },
    Group {
        label: "LOES (Fig. 3)",
        prefix: "loes",
        stems: &[],
    },
    Group {
        label: "Torsion bar",
        prefix: "torsion_bar",
        stems: &[],
    },
    Group {
        label: "Hub",
        prefix: "hub",
        stems: &[],
    },
    Group {
        label: "Plate modes (Fig. 7)",
        prefix: "plate",
        stems: &[],
    },
];

/// The group of the elements no rule of [`GROUPS`] claims.
pub const OTHER: &str = "Other elements";

/// The group of the signal part: reference, controller, potentiometer and amplifiers.
pub const SIGNALS: &str = "Signal part (Fig. 8): reference, controller, potentiometer, amplifiers";

/// The prefixes of the signal blocks drawn in [`SIGNALS`] (with the inputs that feed them).
const SIGNAL_PREFIXES: &[&str] = &["reference", "controller"];

/// The signals of the servo valve's current-feedback amplifier (`servo_valve.drive = 2`,
/// `torque_motor::add_current_amplifier`): electronics, drawn in the signal part with the
/// controller that feeds them.
const CURRENT_AMPLIFIER_STEMS: &[&str] = &["i_demand", "i_error", "K_i", "u_limited"];

/// The prefix of a name (up to its first `.`) and the stem after it (up to the next `.`).
fn prefix_and_stem(name: &str) -> (&str, &str) {
    match name.split_once('.') {
        Some((p, rest)) => (p, rest.split('.').next().unwrap_or(rest)),
        None => (name, ""),
    }
}

/// The index in [`GROUPS`] of the group of an element name, `None` for [`OTHER`].
pub fn group_of(name: &str) -> Option<usize> {
    let (prefix, stem) = prefix_and_stem(name);
    GROUPS
        .iter()
        .position(|g| g.prefix == prefix && (g.stems.is_empty() || g.stems.contains(&stem)))
}

/// The name without its fragment prefix (`servo_valve.R_bob` -> `R_bob`).
fn short(name: &str) -> &str {
    name.split_once('.').map_or(name, |(_, rest)| rest)
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const FONT: f64 = 13.0;
/// Width of a character of the label font (Helvetica/Arial at [`FONT`] px, a little generous).
const CHAR: f64 = 7.4;
const BOX_H: f64 = 22.0;
const JUNCTION_R: f64 = 11.0;
const ROW_GAP: f64 = 14.0;
const COL_GAP: f64 = 44.0;
const PAD: f64 = 14.0;
const TITLE_H: f64 = 22.0;
const GROUP_GAP: f64 = 18.0;
/// The width the rows of groups are filled to (the page shows the figure about 900 px wide).
const PAGE_W: f64 = 960.0;

/// A node of the drawing: its centre, half sizes, and whether it is a circle (junction).
#[derive(Clone, Default)]
struct Node {
    x: f64,
    y: f64,
    hw: f64,
    hh: f64,
    round: bool,
}

/// A laid-out group: its nodes (indices into the graph's elements or the signal list) placed
/// relative to the group's top-left corner, and its size.
struct Laid {
    label: String,
    members: Vec<usize>,
    w: f64,
    h: f64,
}

fn element_label(kind: &ElementKind, name: &str) -> String {
    match kind {
        ElementKind::Zero | ElementKind::One => kind.label().to_string(),
        _ => format!("{}: {}", kind.label(), short(name)),
    }
}

fn size_of(label: &str, round: bool) -> (f64, f64) {
    if round {
        (JUNCTION_R, JUNCTION_R)
    } else {
        (
            (label.chars().count() as f64 * CHAR + 10.0) / 2.0,
            BOX_H / 2.0,
        )
    }
}

/// Lays out one group: `members` are node indices, `adj[n]` the neighbours of node n (in any
/// group), `one_port[n]` whether n is stacked under its neighbour; `entry` the first member
/// bonded to an earlier group, if any. Sets the positions of the members in `nodes` relative to
/// the group's corner and returns its size.
fn lay_group(
    members: &[usize],
    adj: &[Vec<usize>],
    one_port: &[bool],
    entry: Option<usize>,
    nodes: &mut [Node],
) -> (f64, f64) {
    let inside = |n: usize| members.contains(&n);
    let spine: Vec<usize> = members.iter().copied().filter(|&n| !one_port[n]).collect();
    // Breadth-first columns over the multiport members, from the entry (or the first one).
    let mut column = vec![usize::MAX; nodes.len()];
    let mut order: Vec<usize> = Vec::new();
    let starts = entry
        .filter(|e| spine.contains(e))
        .into_iter()
        .chain(spine.iter().copied());
    for start in starts {
        if column[start] != usize::MAX {
            continue;
        }
        column[start] = 0;
        let mut queue = VecDeque::from([start]);
        while let Some(n) = queue.pop_front() {
            order.push(n);
            for &m in &adj[n] {
                if inside(m) && !one_port[m] && column[m] == usize::MAX {
                    column[m] = column[n] + 1;
                    queue.push_back(m);
                }
            }
        }
    }
    // One-port members: under their (first) multiport neighbour in the group, else on their own.
    let mut under: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    let mut alone = Vec::new();
    for &n in members.iter().filter(|&&n| one_port[n]) {
        match adj[n].iter().find(|&&m| inside(m) && !one_port[m]) {
            Some(&m) => under[m].push(n),
            None => alone.push(n),
        }
    }
    let n_cols = order.iter().map(|&n| column[n] + 1).max().unwrap_or(0) + 1;
    let mut cols: Vec<Vec<Vec<usize>>> = vec![Vec::new(); n_cols];
    for &n in &order {
        let mut stack = vec![n];
        stack.extend(&under[n]);
        cols[column[n]].push(stack);
    }
    for n in alone {
        cols[n_cols - 1].push(vec![n]);
    }
    // Within a column, the stacks in the order of their neighbours: a first sweep left to right
    // by the columns already placed, then sweeps by all neighbours (barycentres, which shortens
    // and uncrosses the bonds), ties kept in order.
    let mut rank = vec![f64::NAN; nodes.len()];
    let stack_key = |s: &Vec<usize>, rank: &[f64]| {
        let r: Vec<f64> = s
            .iter()
            .flat_map(|&n| adj[n].iter())
            .filter(|&&m| inside(m) && !s.contains(&m) && !rank[m].is_nan())
            .map(|&m| rank[m])
            .collect();
        if r.is_empty() {
            f64::MAX
        } else {
            r.iter().sum::<f64>() / r.len() as f64
        }
    };
    let place = |stacks: &[Vec<usize>], rank: &mut [f64], nodes: &mut [Node]| {
        let mut y = TITLE_H + PAD;
        for stack in stacks {
            for &n in stack {
                nodes[n].y = y + nodes[n].hh;
                rank[n] = nodes[n].y;
                y += 2.0 * nodes[n].hh + ROW_GAP;
            }
            y += ROW_GAP / 2.0;
        }
        y
    };
    for _ in 0..4 {
        for stacks in cols.iter_mut() {
            let keys: Vec<f64> = stacks.iter().map(|s| stack_key(s, &rank)).collect();
            let mut order: Vec<usize> = (0..stacks.len()).collect();
            order.sort_by(|&i, &j| keys[i].total_cmp(&keys[j]));
            *stacks = order.iter().map(|&i| stacks[i].clone()).collect();
            place(stacks, &mut rank, nodes);
        }
    }
    let mut x = PAD;
    let mut h: f64 = 0.0;
    for stacks in cols.iter().filter(|s| !s.is_empty()) {
        let w = stacks
            .iter()
            .flatten()
            .map(|&n| nodes[n].hw)
            .fold(0.0, f64::max);
        for &n in stacks.iter().flatten() {
            nodes[n].x = x + w;
        }
        h = h.max(place(stacks, &mut rank, nodes));
        x += 2.0 * w + COL_GAP;
    }
    (x - COL_GAP + PAD, h + PAD - ROW_GAP)
}

/// The point where the segment from the centre of `a` towards the centre of `b` leaves `a`.
fn rim(a: &Node, b: &Node) -> (f64, f64) {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len = (dx * dx + dy * dy).sqrt().max(1e-9);
    let t = if a.round {
        a.hw / len
    } else {
        let tx = if dx.abs() > 1e-9 {
            a.hw / dx.abs()
        } else {
            f64::MAX
        };
        let ty = if dy.abs() > 1e-9 {
            a.hh / dy.abs()
        } else {
            f64::MAX
        };
        tx.min(ty)
    };
    (a.x + dx * t, a.y + dy * t)
}

/// A bond from `a` to `b`: a line with a half arrow at `b` and, when known, the causal stroke
/// at `b` (`Some(true)`) or at `a` (`Some(false)`).
fn bond(out: &mut String, a: &Node, b: &Node, stroke_at_head: Option<bool>, class: &str) {
    let (x1, y1) = rim(a, b);
    let (x2, y2) = rim(b, a);
    let (dx, dy) = (x2 - x1, y2 - y1);
    let len = (dx * dx + dy * dy).sqrt().max(1e-9);
    let (ux, uy) = (dx / len, dy / len);
    // Normal on the left of the direction of power.
    let (nx, ny) = (-uy, ux);
    let _ = write!(
        out,
        "<path class=\"{class}\" d=\"M{x1:.1},{y1:.1} L{x2:.1},{y2:.1} L{:.1},{:.1}",
        x2 - 9.0 * ux + 6.0 * nx,
        y2 - 9.0 * uy + 6.0 * ny
    );
    if let Some(head) = stroke_at_head {
        let (sx, sy) = if head { (x2, y2) } else { (x1, y1) };
        let _ = write!(
            out,
            " M{:.1},{:.1} L{:.1},{:.1}",
            sx + 6.0 * nx,
            sy + 6.0 * ny,
            sx - 6.0 * nx,
            sy - 6.0 * ny
        );
    }
    out.push_str("\"/>\n");
}

/// The SVG of the bond graph `g`, its power part grouped by [`GROUPS`] and its signal part
/// apart; `strokes` are the causal strokes per bond (`true`: at the head), from the compiled
/// model, or `None` when causality could not be assigned.
pub fn svg(g: &BondGraph, strokes: Option<&[bool]>) -> String {
    let elements = g.elements();
    let signals = g.signals();
    let ne = elements.len();
    // Nodes: the elements, then the signal blocks of the signal part, then stubs naming the
    // signals that feed it from elsewhere.
    let sources = |k: &SignalKind| -> Vec<usize> {
        match k {
            SignalKind::Gain(_, Some(x))
            | SignalKind::Function(_, Some(x))
            | SignalKind::Integrator(Some(x))
            | SignalKind::Port(Some(x)) => vec![x.index()],
            SignalKind::Sum(t) => t.iter().map(|(_, x)| x.index()).collect(),
            SignalKind::Product(a, b) => vec![a.index(), b.index()],
            _ => vec![],
        }
    };
    // Follows a signal back through pass-through ports.
    let through_ports = |mut s: usize| {
        while let SignalKind::Port(Some(x)) = &signals[s].kind {
            s = x.index();
        }
        s
    };
    let in_signal_part = |s: usize| {
        let (p, stem) = prefix_and_stem(&signals[s].name);
        SIGNAL_PREFIXES.contains(&p)
            || (p == "servo_valve" && CURRENT_AMPLIFIER_STEMS.contains(&stem))
    };
    let mut sig_nodes: Vec<usize> = (0..signals.len()).filter(|&s| in_signal_part(s)).collect();
    // The inputs that feed the signal part directly.
    let inputs: Vec<usize> = (0..signals.len())
        .filter(|&s| matches!(signals[s].kind, SignalKind::Input))
        .filter(|&s| {
            sig_nodes
                .iter()
                .any(|&t| sources(&signals[t].kind).contains(&s))
        })
        .collect();
    sig_nodes.splice(0..0, inputs);
    let sig_of = |s: usize| sig_nodes.iter().position(|&t| t == s).map(|i| ne + i);
    // Signal edges (node to node) and the names of signals from elsewhere (stubs).
    let mut stubs: Vec<String> = Vec::new();
    let mut sig_edges: Vec<(usize, usize)> = Vec::new();
    for (i, &t) in sig_nodes.iter().enumerate() {
        for s in sources(&signals[t].kind) {
            let s = through_ports(s);
            let from = match sig_of(s) {
                Some(n) => n,
                None => {
                    let stub = format!("from {}", signals[s].name);
                    let k = stubs.iter().position(|x| *x == stub).unwrap_or_else(|| {
                        stubs.push(stub);
                        stubs.len() - 1
                    });
                    ne + sig_nodes.len() + k
                }
            };
            sig_edges.push((from, ne + i));
        }
    }
    // Modulated elements driven from the signal part (the amplifier's voltage on the coil): a
    // stub naming the element, in the signal part, under the block that drives it.
    let mut drive_stubs: Vec<usize> = Vec::new();

    for (e, el) in elements.iter().enumerate() {
        let m = match &el.kind {
            ElementKind::Se(v) | ElementKind::Sf(v) | ElementKind::Tf(v) | ElementKind::Gy(v) => {
                match v {
                    hydraulic_slewing_plate::bond_graph::SourceValue::Signal(x) => Some(x.index()),
                    _ => None,
                }
            }
            _ => None,
        };
        if let Some(n) = m.map(through_ports).and_then(sig_of) {
            stubs.push(format!("to {}", elements[e].name));
            drive_stubs.push(ne + sig_nodes.len() + stubs.len() - 1);
            sig_edges.push((n, ne + sig_nodes.len() + stubs.len() - 1));
        }
    }
    let n_nodes = ne + sig_nodes.len() + stubs.len();
    let mut labels: Vec<String> = Vec::with_capacity(n_nodes);
    let mut titles: Vec<String> = Vec::with_capacity(n_nodes);
    let mut nodes = vec![Node::default(); n_nodes];
    let mut classes: Vec<&str> = Vec::with_capacity(n_nodes);
    for el in elements {
        labels.push(element_label(&el.kind, &el.name));
        titles.push(el.name.clone());
        classes.push(match el.kind {
            ElementKind::Zero | ElementKind::One => "j",
            ElementKind::C(_)
            | ElementKind::I(_)
            | ElementKind::IField(_)
            | ElementKind::CField(..) => "st",
            ElementKind::R(..) => "r",
            ElementKind::Se(_) | ElementKind::Sf(_) => "src",
            ElementKind::Tf(_) | ElementKind::Gy(_) => "tf",
        });
    }
    for &s in &sig_nodes {
        let sg = &signals[s];
        let name = short(&sg.name);
        labels.push(match &sg.kind {
            SignalKind::Input => format!("input {name}"),
            SignalKind::Gain(k, _) => format!("{name} = {}", crate::docpage::text::short(k.v)),
            SignalKind::Sum(_) => format!("\u{3a3} {name}"),
            SignalKind::Integrator(_) => format!("\u{222b} {name}"),
            SignalKind::Function(..) => format!("f: {name}"),
            SignalKind::Constant(c) => format!("{name} = {}", crate::docpage::text::short(c.v)),
            _ => format!("{} {name}", sg.kind.label()),
        });
        titles.push(sg.name.clone());
        classes.push("sig");
    }
    for s in &stubs {
        // The label names the far end by its short name; the title in full.
        let (dir, name) = s.split_once(' ').unwrap_or(("", s));
        labels.push(match elements.iter().find(|e| e.name == name) {
            Some(e) => format!("{dir} {}", element_label(&e.kind, name)),
            None => format!("{dir} {}", short(name)),
        });
        titles.push(s.clone());
        classes.push("stub");
    }
    for (n, node) in nodes.iter_mut().enumerate() {
        let round = classes[n] == "j";
        let (hw, hh) = size_of(&labels[n], round);
        *node = Node {
            hw,
            hh,
            round,
            ..Node::default()
        };
    }
    // Adjacency: bonds for elements, signal edges for the signal part.
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n_nodes];
    for b in g.bonds() {
        let (a, c) = (b.from.index(), b.to.index());
        adj[a].push(c);
        adj[c].push(a);
    }
    let degree: Vec<usize> = adj.iter().map(Vec::len).collect();
    for &(a, c) in &sig_edges {
        adj[a].push(c);
        adj[c].push(a);
    }
    let mut one_port = vec![false; n_nodes];
    for (n, flag) in one_port.iter_mut().enumerate().take(ne) {
        *flag = degree[n] == 1
            && !matches!(
                elements[n].kind,
                ElementKind::Zero | ElementKind::One | ElementKind::Tf(_) | ElementKind::Gy(_)
            );
    }
    // Groups, in order; the signal part last, on a row of its own.
    let mut group_members: Vec<Vec<usize>> = vec![Vec::new(); GROUPS.len() + 1];
    for (e, el) in elements.iter().enumerate() {
        group_members[group_of(&el.name).unwrap_or(GROUPS.len())].push(e);
    }
    let mut laid: Vec<Laid> = Vec::new();
    let mut earlier: Vec<usize> = Vec::new();
    for (i, members) in group_members.iter().enumerate() {
        if members.is_empty() {
            continue;
        }
        let entry = members
            .iter()
            .copied()
            .find(|&n| adj[n].iter().any(|m| earlier.contains(m)));
        let (w, h) = lay_group(members, &adj, &one_port, entry, &mut nodes);
        let label = GROUPS.get(i).map_or(OTHER, |g| g.label).to_string();
        let w = w.max(label.chars().count() as f64 * CHAR + 2.0 * PAD);
        laid.push(Laid {
            label,
            members: members.clone(),
            w,
            h,
        });
        earlier.extend(members);
    }
    let signal_members: Vec<usize> = (ne..n_nodes).collect();
    let signal_group = (!sig_nodes.is_empty()).then(|| {
        let (w, h) = lay_signals(&signal_members, &sig_edges, &drive_stubs, &mut nodes);
        Laid {
            label: SIGNALS.to_string(),
            members: signal_members.clone(),
            w: w.max(SIGNALS.chars().count() as f64 * CHAR + 2.0 * PAD),
            h,
        }
    });
    // Rows of groups filled to the page width; the signal part on the last row.
    let mut placed: Vec<(f64, f64, Laid)> = Vec::new();
    let (mut x, mut y, mut row_h) = (0.0_f64, 0.0_f64, 0.0_f64);
    for group in laid {
        if x > 0.0 && x + group.w > PAGE_W {
            x = 0.0;
            y += row_h + GROUP_GAP;
            row_h = 0.0;
        }
        row_h = row_h.max(group.h);
        placed.push((x, y, group));
        x += placed.last().map_or(0.0, |p| p.2.w) + GROUP_GAP;
    }
    if let Some(group) = signal_group {
        y += row_h + GROUP_GAP;
        row_h = group.h;
        placed.push((0.0, y, group));
    }
    let total_h = y + row_h;
    let total_w = placed.iter().map(|(x, _, l)| x + l.w).fold(0.0, f64::max);
    for (x, y, l) in &placed {
        for &n in &l.members {
            nodes[n].x += x;
            nodes[n].y += y;
        }
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{total_w:.0}\" height=\"{total_h:.0}\" \
         viewBox=\"0 0 {total_w:.0} {total_h:.0}\" font-family=\"Helvetica, Arial, sans-serif\" \
         font-size=\"{FONT}\">"
    );
    out.push_str(
        "<style>\
         .grp{fill:#f7f7f2;stroke:#999;stroke-width:1}\
         .sgrp{fill:#f2f5fa;stroke:#99a;stroke-width:1;stroke-dasharray:5 3}\
         .gl{font-weight:bold;fill:#333}\
         .b{fill:none;stroke:#222;stroke-width:1.4}\
         .x{fill:none;stroke:#c06020;stroke-width:1.1;opacity:0.7}\
         .s{fill:none;stroke:#557;stroke-width:1.1;stroke-dasharray:4 3}\
         .n rect{fill:#fff;stroke:#444}\
         .st rect{fill:#e6f0ff}.r rect{fill:#ffece6}.src rect{fill:#e9f7e4}.tf rect{fill:#f0f0f0}\
         .sig rect{fill:#fff;stroke:#557}.stub rect{fill:none;stroke:none}\
         .j circle{fill:#fff;stroke:#222;stroke-width:1.4}\
         </style>\n<defs><marker id=\"a\" viewBox=\"0 0 10 10\" refX=\"10\" refY=\"5\" \
         markerWidth=\"7\" markerHeight=\"7\" orient=\"auto\"><path d=\"M0,0 L10,5 L0,10 z\" \
         fill=\"#557\"/></marker></defs>\n",
    );
    for (x, y, l) in &placed {
        let class = if l.label == SIGNALS { "sgrp" } else { "grp" };
        let _ = writeln!(
            out,
            "<rect class=\"{class}\" x=\"{x:.1}\" y=\"{y:.1}\" width=\"{:.1}\" height=\"{:.1}\" \
             rx=\"6\"/><text class=\"gl\" x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            l.w,
            l.h,
            x + PAD,
            y + 18.0,
            esc(&l.label)
        );
    }
    let group_index: Vec<usize> = {
        let mut gi = vec![usize::MAX; n_nodes];
        for (k, (_, _, l)) in placed.iter().enumerate() {
            for &n in &l.members {
                gi[n] = k;
            }
        }
        gi
    };
    for (i, b) in g.bonds().iter().enumerate() {
        let (a, c) = (b.from.index(), b.to.index());
        let class = if group_index[a] == group_index[c] {
            "b"
        } else {
            "x"
        };
        bond(&mut out, &nodes[a], &nodes[c], strokes.map(|s| s[i]), class);
    }
    for &(a, c) in &sig_edges {
        let (x1, y1) = rim(&nodes[a], &nodes[c]);
        let (x2, y2) = rim(&nodes[c], &nodes[a]);
        let _ = writeln!(
            out,
            "<path class=\"s\" d=\"M{x1:.1},{y1:.1} L{x2:.1},{y2:.1}\" marker-end=\"url(#a)\"/>"
        );
    }
    for (n, node) in nodes.iter().enumerate() {
        let class = classes[n];
        let _ = write!(
            out,
            "<g class=\"n {class}\"><title>{}</title>",
            esc(&titles[n])
        );
        if node.round {
            let _ = write!(
                out,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"{JUNCTION_R}\"/>",
                node.x, node.y
            );
        } else {
            let _ = write!(
                out,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" rx=\"3\"/>",
                node.x - node.hw,
                node.y - node.hh,
                2.0 * node.hw,
                2.0 * node.hh
            );
        }
        let _ = writeln!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text></g>",
            node.x,
            node.y + FONT * 0.35,
            esc(&labels[n])
        );
    }
    out.push_str("</svg>\n");
    out
}

/// Lays out the signal part: columns by the longest path from its sources along the signal
/// edges (each block right of what feeds it), rows in order of creation; the nodes `under` in
/// the column of what feeds them, below it.
fn lay_signals(
    members: &[usize],
    edges: &[(usize, usize)],
    under: &[usize],
    nodes: &mut [Node],
) -> (f64, f64) {
    let mut column = vec![0usize; nodes.len()];
    // Longest path, at most `members.len()` rounds (a loop through an integrator stops there).
    for _ in 0..members.len() {
        let mut changed = false;
        for &(a, b) in edges {
            if column[b] < column[a] + 1 && column[a] < members.len() {
                column[b] = column[a] + 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    // Then each block as far right as what it feeds allows (an input beside its first use).
    for _ in 0..members.len() {
        let mut changed = false;
        for &a in members {
            let next = edges.iter().filter(|e| e.0 == a).map(|e| column[e.1]).min();
            if let Some(c) = next.filter(|&c| c > column[a] + 1) {
                column[a] = c - 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    for &(a, b) in edges {
        if under.contains(&b) {
            column[b] = column[a];
        }
    }
    let n_cols = members.iter().map(|&n| column[n]).max().unwrap_or(0) + 1;
    let mut x = PAD;
    let mut h: f64 = 0.0;
    for c in 0..n_cols {
        let mut col: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&n| column[n] == c)
            .collect();
        // The blocks on the main path first, the ones fed by nothing below them.
        col.sort_by_key(|&n| (under.contains(&n), !edges.iter().any(|e| e.1 == n)));
        let w = col.iter().map(|&n| nodes[n].hw).fold(0.0, f64::max);
        let mut y = TITLE_H + PAD;
        for n in col {
            nodes[n].x = x + w;
            nodes[n].y = y + nodes[n].hh;
            y += 2.0 * nodes[n].hh + ROW_GAP;
        }
        h = h.max(y);
        x += 2.0 * w + COL_GAP * 0.5;
    }
    (x - COL_GAP * 0.5 + PAD, h + PAD - ROW_GAP)
}

#[cfg(test)]
mod tests {
    use super::*;
    use hydraulic_slewing_plate::model::compose::bond_graph;

    /// The figure's SVG for the figure's settings and then `more`, and the graph.
    fn figure(more: &[(&str, &str)]) -> (String, BondGraph) {
        let p = super::super::figures::figure_parameters(more).unwrap();
        let g = bond_graph(&p).unwrap();
        let c = g.compile().unwrap();
        (svg(&g, Some(c.causal_strokes())), g)
    }

    /// Checks the SVG is well-formed, holds every element of `g` exactly once (as the title of
    /// one node) and the label of every group that has elements, and no element left to
    /// [`OTHER`]; returns the group labels found.
    fn check(svg: &str, g: &BondGraph) -> Vec<String> {
        let doc = roxmltree::Document::parse(svg).expect("well-formed SVG");
        let titles: Vec<&str> = doc
            .descendants()
            .filter(|n| n.has_tag_name("title"))
            .filter_map(|n| n.text())
            .collect();
        for el in g.elements() {
            let n = titles.iter().filter(|t| **t == el.name).count();
            assert_eq!(n, 1, "{} drawn {n} times", el.name);
            assert!(group_of(&el.name).is_some(), "{} in no group", el.name);
        }
        let texts: Vec<String> = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text().map(str::to_string))
            .collect();
        for group in GROUPS {
            let used = g
                .elements()
                .iter()
                .any(|e| group_of(&e.name).is_some_and(|i| std::ptr::eq(&GROUPS[i], group)));
            assert_eq!(
                texts.iter().any(|t| t == group.label),
                used,
                "{}",
                group.label
            );
        }
        assert!(!texts.iter().any(|t| t == OTHER), "{svg}");
        assert!(texts.iter().any(|t| t == SIGNALS));
        // Each bond is one path of a half arrow with its causal stroke (two subpaths).
        let bonds = doc
            .descendants()
            .filter(|n| matches!(n.attribute("class"), Some("b") | Some("x")))
            .filter(|n| {
                n.attribute("d")
                    .is_some_and(|d| d.matches('M').count() == 2)
            })
            .count();
        assert_eq!(bonds, g.bonds().len());
        texts
    }

    #[test]
    fn the_figure_shows_every_element_once_grouped_as_the_paper() {
        // The configuration of the page: the full servo valve, a two-mode plate.
        let (svg, g) = figure(&[]);
        let texts = check(&svg, &g);
        for label in [
            GROUPS[0].label,
            GROUPS[1].label,
            GROUPS[2].label,
            "Torsion bar",
            "Hub",
            "Plate modes (Fig. 7)",
        ] {
            assert!(texts.iter().any(|t| t == label), "{label}");
        }
        // Parameter names as the paper writes them, and the controller's gains.
        for label in [
            "R: R_bob",
            "I: L_bob",
            "GY: k_phi",
            "TF: D_m",
            "A1 = 2",
            "A2 = 10",
        ] {
            assert!(texts.iter().any(|t| t == label), "{label}");
        }
        // The amplifier's output drives the coil's voltage source (BG1).
        assert!(svg.contains("<title>to servo_valve.amplifier</title>"));
        assert!(texts.iter().any(|t| t == "to MSe: amplifier"));
        assert!(svg.contains("<title>from servo_valve.theta_a</title>"));
        if let Ok(path) = std::env::var("HSP_BOND_GRAPH_SVG") {
            std::fs::write(path, &svg).unwrap();
        }
    }

    #[test]
    fn the_loes_and_the_paper_plate_fall_in_groups_too() {
        let (svg, g) = figure(&[
            ("hydraulics.model", "1"),
            ("plate.formulation", "1"),
            ("plate.N", "3"),
        ]);
        let texts = check(&svg, &g);
        assert!(texts.iter().any(|t| t == "LOES (Fig. 3)"));
    }
}
