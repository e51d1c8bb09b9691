//! The part vocabulary: what a part label means (a base, a grip, a door, a wheel, …) and which
//! joint types it allows. It is data, `assets/vocabulary.toml` (documented there), built into the
//! binary; `--vocab FILE` extends or overrides it ([`Vocabulary::extended_with`]).
//!
//! A label picks a class ([`Vocabulary::classify`]); the class gives the allowed joint types, and
//! a motion word in the label (`hinge_door`, `slider_lid`) or the geometry
//! ([`super::evidence`]) chooses among them.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::{Arc, OnceLock};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::joint::JointKind;

/// The built-in vocabulary's text.
pub const BUILTIN_VOCABULARY: &str = include_str!("../../assets/vocabulary.toml");

/// Why a vocabulary file was refused.
#[derive(Debug, Error)]
pub enum VocabularyError {
    #[error("{source_name}: {message}")]
    Parse { source_name: String, message: String },
    #[error("{source_name}: class `{class}`: {message}")]
    Class { source_name: String, class: String, message: String },
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
}

/// What a class of parts does in an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// What an object is built on: the preferred root of its tree.
    Base,
    /// Mounted on a part to move it; marks that part's front.
    Grip,
    /// Moves relative to its parent.
    Movable,
    /// Does not move relative to its parent.
    Rigid,
}

/// A geometric test that may choose another joint type the class allows ([`super::evidence`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GeometryTest {
    /// A door with a parallel panel overlapping it in a second plane slides.
    SlidingPanel,
    /// A round lid centred on a round body lifts along the body's axis.
    LiftOff,
    /// A handle spanning a round body across its axis swings about its ends.
    SwingHandle,
    /// A switch standing out of its mount farther than it is wide is a lever: it turns.
    ToggleLever,
}

/// How a joint type is fitted to the geometry of a part ([`super::assign::fit_joint`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Template {
    /// Rigid.
    #[default]
    Fixed,
    /// Slides out of the parent's front face.
    Drawer,
    /// Slides in the panel's own plane, towards the side where it has room.
    SlidingPanel,
    /// Pressed into the parent.
    Button,
    /// Turns about the mount normal through the part's centre.
    Knob,
    /// Turns about the mount normal through one end of a bar: the end away from a grip on it,
    /// else the end nearer the middle of what it is mounted on (a lever, a latch).
    Lever,
    /// Tilts about its in-plane axis through its centre (a rocker switch).
    Rocker,
    /// Swings on a door's edge (a vertical mount normal is not trusted: a door found resting on
    /// a shelf still opens sideways).
    Hinge,
    /// Swings on a lid's edge.
    LidHinge,
    /// Lifts along the round parent's axis.
    LiftOff,
    /// Swings about the line through a handle's ends.
    Swing,
    /// Spins about its own round axis (a wheel).
    Spin,
    /// Turns about the mount normal through its centre without limits (a turntable).
    Turn,
}

impl Template {
    /// The template of a joint type when the class names none.
    #[must_use]
    pub fn default_for(kind: JointKind) -> Self {
        match kind {
            JointKind::Fixed => Template::Fixed,
            JointKind::Prismatic => Template::Drawer,
            JointKind::Revolute => Template::Hinge,
            JointKind::Continuous => Template::Spin,
        }
    }

    /// A door's or lid's hinge: turns about one of the part's edges, which a person may move to
    /// the opposite edge.
    #[must_use]
    pub fn is_hinge(self) -> bool {
        matches!(self, Template::Hinge | Template::LidHinge)
    }
}

/// One class of parts.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartClass {
    pub name: String,
    pub role: Role,
    /// Allowed joint types, the default first.
    pub joints: Vec<JointKind>,
    #[serde(default)]
    pub tests: Vec<GeometryTest>,
    /// Joint type name → template, where it differs from [`Template::default_for`].
    #[serde(default)]
    pub templates: BTreeMap<String, Template>,
    /// Boards and boxes: the fitter keeps a cuboid unless another kind fits clearly better.
    #[serde(default)]
    pub prefer_box: bool,
    /// Mounted on a door or lid to open or lock it, at its free edge (grips always are).
    #[serde(default)]
    pub marks_free_edge: bool,
    /// Classes this class is typically attached to.
    #[serde(default)]
    pub parents: Vec<String>,
    pub words: Vec<String>,
}

impl PartClass {
    /// The joint type the class gives when nothing else decides.
    #[must_use]
    pub fn default_joint(&self) -> JointKind {
        self.joints.first().copied().unwrap_or(JointKind::Fixed)
    }

    #[must_use]
    pub fn allows(&self, kind: JointKind) -> bool {
        self.joints.contains(&kind)
    }

    /// How this class fits a joint of type `kind`.
    #[must_use]
    pub fn template(&self, kind: JointKind) -> Template {
        if kind == JointKind::Fixed {
            return Template::Fixed;
        }
        self.templates.get(kind.name()).copied().unwrap_or_else(|| Template::default_for(kind))
    }
}

/// How a label was read.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelMatch<'v> {
    pub class: &'v PartClass,
    /// The vocabulary word that matched.
    pub word: String,
    /// Whether a whole token matched (else a word inside a compound token).
    pub whole_token: bool,
    /// A motion word of the label and the type it names (whether or not the class allows it).
    pub motion: Option<(String, JointKind)>,
}

impl LabelMatch<'_> {
    /// The motion word's type when the class allows it.
    #[must_use]
    pub fn allowed_motion(&self) -> Option<JointKind> {
        self.motion.as_ref().map(|(_, k)| *k).filter(|k| self.class.allows(*k))
    }
}

/// Objects whose category changes what a label word names (a toilet's seat hinges up like its
/// lid, where a chair's seat is rigid).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CategoryRule {
    /// Category words (lowercase): the rule holds in an object whose category has one as a token.
    pub words: Vec<String>,
    /// Label word → the class it names in those objects.
    pub classes: BTreeMap<String, String>,
}

/// The vocabulary: classes in priority order, motion words and category rules.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vocabulary {
    #[serde(default)]
    motion_words: BTreeMap<String, JointKind>,
    #[serde(rename = "category", default)]
    categories: Vec<CategoryRule>,
    #[serde(rename = "class", default)]
    classes: Vec<PartClass>,
}

impl Default for Vocabulary {
    fn default() -> Self {
        Self::builtin().as_ref().clone()
    }
}

/// The lowercase alphabetic tokens of a label (`Door_Left2` → `door`, `left`).
pub fn label_tokens(label: &str) -> impl Iterator<Item = String> + '_ {
    label.split(|c: char| !c.is_ascii_alphabetic()).filter(|t| !t.is_empty()).map(str::to_ascii_lowercase)
}

impl Vocabulary {
    /// The built-in vocabulary (`assets/vocabulary.toml`), parsed once.
    ///
    /// # Panics
    /// Never at run time: the built-in file is checked by a unit test.
    #[must_use]
    pub fn builtin() -> Arc<Vocabulary> {
        static BUILTIN: OnceLock<Arc<Vocabulary>> = OnceLock::new();
        BUILTIN
            .get_or_init(|| {
                #[allow(clippy::expect_used)] // the built-in file is tested to parse
                Arc::new(Vocabulary::parse(BUILTIN_VOCABULARY, "assets/vocabulary.toml").expect("the built-in vocabulary parses"))
            })
            .clone()
    }

    /// Parses vocabulary TOML; `source_name` names it in errors.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, VocabularyError> {
        let vocab = Self::deserialize(text, source_name)?;
        vocab.validate(source_name)?;
        Ok(vocab)
    }

    /// The TOML as it stands, not yet validated (an extension may name classes of the base).
    fn deserialize(text: &str, source_name: &str) -> Result<Self, VocabularyError> {
        toml::from_str(text).map_err(|e| VocabularyError::Parse { source_name: source_name.to_owned(), message: e.to_string() })
    }

    /// Reads a vocabulary file and lays it over `self`: classes of the same name are replaced,
    /// new classes are tried before the existing ones, motion words are added or replaced.
    pub fn extended_with_file(&self, path: &Path) -> Result<Self, VocabularyError> {
        let bytes = crate::io::read_bytes(path)?;
        let name = path.display().to_string();
        let text =
            String::from_utf8(bytes).map_err(|_| VocabularyError::Parse { source_name: name.clone(), message: "not UTF-8 text".into() })?;
        let merged = self.extended_with(Self::deserialize(&text, &name)?);
        merged.validate(&name)?;
        Ok(merged)
    }

    /// `self` with `extra` laid over it (see [`Self::extended_with_file`]).
    #[must_use]
    pub fn extended_with(&self, extra: Vocabulary) -> Self {
        let mut classes = Vec::new();
        let mut rest = self.classes.clone();
        for class in extra.classes {
            if let Some(slot) = rest.iter_mut().find(|c| c.name == class.name) {
                *slot = class;
            } else {
                classes.push(class);
            }
        }
        classes.extend(rest);
        let mut motion_words = self.motion_words.clone();
        motion_words.extend(extra.motion_words);
        let categories = extra.categories.into_iter().chain(self.categories.iter().cloned()).collect();
        Self { motion_words, categories, classes }
    }

    fn validate(&self, source_name: &str) -> Result<(), VocabularyError> {
        let class_err =
            |class: &str, message: String| VocabularyError::Class { source_name: source_name.to_owned(), class: class.to_owned(), message };
        let mut seen = std::collections::BTreeSet::new();
        for c in &self.classes {
            if !seen.insert(c.name.as_str()) {
                return Err(class_err(&c.name, "defined twice".into()));
            }
            if c.joints.is_empty() {
                return Err(class_err(
                    &c.name,
                    "`joints` is empty; expected at least one of fixed, revolute, prismatic, continuous".into(),
                ));
            }
            if c.words.is_empty() {
                return Err(class_err(&c.name, "`words` is empty".into()));
            }
            if let Some(k) = c.templates.keys().find(|k| JointKind::from_name(k).is_none_or(|kind| !c.joints.contains(&kind))) {
                return Err(class_err(&c.name, format!("`templates` key `{k}`: expected one of the class's `joints`")));
            }
            if let Some(w) = c.words.iter().find(|w| w.is_empty() || !w.chars().all(|ch| ch.is_ascii_lowercase())) {
                return Err(class_err(
                    &c.name,
                    format!("word {w:?}: expected lowercase letters a-z only (labels are split at anything else)"),
                ));
            }
        }
        for c in &self.classes {
            if let Some(p) = c.parents.iter().find(|p| !seen.contains(p.as_str())) {
                return Err(class_err(&c.name, format!("parent class `{p}` is not defined")));
            }
        }
        for rule in &self.categories {
            let lowercase = |w: &String| !w.is_empty() && w.chars().all(|ch| ch.is_ascii_lowercase());
            if let Some(w) = rule.words.iter().chain(rule.classes.keys()).find(|w| !lowercase(w)) {
                return Err(VocabularyError::Parse {
                    source_name: source_name.to_owned(),
                    message: format!("category rule word {w:?}: expected lowercase letters a-z only"),
                });
            }
            if let Some(c) = rule.classes.values().find(|c| !seen.contains(c.as_str())) {
                return Err(VocabularyError::Parse {
                    source_name: source_name.to_owned(),
                    message: format!("category rule for {:?}: class `{c}` is not defined", rule.words),
                });
            }
        }
        if let Some(w) = self.motion_words.keys().find(|w| w.is_empty() || !w.chars().all(|ch| ch.is_ascii_lowercase())) {
            return Err(VocabularyError::Parse {
                source_name: source_name.to_owned(),
                message: format!("motion word {w:?}: expected lowercase letters a-z only"),
            });
        }
        Ok(())
    }

    /// The classes, in priority order.
    #[must_use]
    pub fn classes(&self) -> &[PartClass] {
        &self.classes
    }

    #[must_use]
    pub fn class(&self, name: &str) -> Option<&PartClass> {
        self.classes.iter().find(|c| c.name == name)
    }

    /// Reads a label (module docs of `assets/vocabulary.toml`): the class of its highest-priority
    /// matching token and its motion word, if any. `None`: no token names a class.
    #[must_use]
    pub fn classify(&self, label: &str) -> Option<LabelMatch<'_>> {
        let tokens: Vec<String> = label_tokens(label).collect();
        let motion = tokens.iter().find_map(|t| self.motion_words.get(t).map(|k| (t.clone(), *k)));
        // Per token: (class index, word, whole token); within a class the last token wins (the
        // head noun: `cabinet_body` → body).
        let matches = tokens.iter().enumerate().filter_map(|(k, t)| self.token_class(t).map(|m| (k, m)));
        let (_, (index, word, whole_token)) = matches.min_by_key(|(k, (i, _, whole))| (*i, !*whole, std::cmp::Reverse(*k)))?;
        Some(LabelMatch { class: &self.classes[index], word, whole_token, motion })
    }

    /// Reads a label of a part of an object of `category`: a category rule's word in the label
    /// names the rule's class (the last such word); else as [`Self::classify`].
    #[must_use]
    pub fn classify_in(&self, label: &str, category: &str) -> Option<LabelMatch<'_>> {
        let category_tokens: Vec<String> = label_tokens(category).collect();
        let rule = self.categories.iter().find(|r| r.words.iter().any(|w| category_tokens.contains(w)));
        let tokens: Vec<String> = label_tokens(label).collect();
        let overridden = rule.and_then(|r| tokens.iter().rev().find_map(|t| Some((t.clone(), self.class(r.classes.get(t)?)?))));
        match overridden {
            Some((word, class)) => {
                let motion = tokens.iter().find_map(|t| self.motion_words.get(t).map(|k| (t.clone(), *k)));
                Some(LabelMatch { class, word, whole_token: true, motion })
            }
            None => self.classify(label),
        }
    }

    /// The class a single token names: the whole token if it is a word, else the word inside it
    /// that ends last (a match inside a longer match, a motion word included, does not count).
    fn token_class(&self, token: &str) -> Option<(usize, String, bool)> {
        if let Some(i) = self.classes.iter().position(|c| c.words.iter().any(|w| w == token)) {
            return Some((i, token.to_owned(), true));
        }
        if self.motion_words.contains_key(token) {
            return None;
        }
        // (start, end, class index or None for a motion word, word)
        let mut found: Vec<(usize, usize, Option<usize>, &str)> = Vec::new();
        let words = self
            .classes
            .iter()
            .enumerate()
            .flat_map(|(i, c)| c.words.iter().map(move |w| (Some(i), w.as_str())))
            .chain(self.motion_words.keys().map(|w| (None, w.as_str())));
        for (class, word) in words {
            if word.len() < 3 {
                continue;
            }
            let mut from = 0;
            while let Some(at) = token[from..].find(word) {
                let start = from + at;
                found.push((start, start + word.len(), class, word));
                from = start + 1;
            }
        }
        let inside_longer =
            |a: &(usize, usize, Option<usize>, &str)| found.iter().any(|b| b.0 <= a.0 && a.1 <= b.1 && (b.1 - b.0) > (a.1 - a.0));
        found
            .iter()
            .filter(|m| !inside_longer(m))
            .filter_map(|m| m.2.map(|class| (m.1, m.1 - m.0, class, m.3)))
            .max_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(&b.1)).then(b.2.cmp(&a.2)))
            .map(|(_, _, class, word)| (class, word.to_owned(), false))
    }

    fn role(&self, label: &str) -> Option<Role> {
        self.classify(label).map(|m| m.class.role)
    }

    /// A part an object is built on: the preferred root of its tree.
    #[must_use]
    pub fn is_base(&self, label: &str) -> bool {
        self.role(label) == Some(Role::Base)
    }

    /// A grip mounted on a part to move it.
    #[must_use]
    pub fn is_grip(&self, label: &str) -> bool {
        self.role(label) == Some(Role::Grip)
    }

    /// The joint type a label alone calls for: its motion word when its class allows it, else
    /// the class default; unknown labels are fixed (geometry may still decide,
    /// [`super::evidence`]).
    #[must_use]
    pub fn joint_kind(&self, label: &str) -> JointKind {
        self.classify(label).map_or(JointKind::Fixed, |m| m.allowed_motion().unwrap_or_else(|| m.class.default_joint()))
    }

    /// Whether the label names a board or a box ([`PartClass::prefer_box`]).
    #[must_use]
    pub fn prefers_box(&self, label: &str) -> bool {
        self.classify(label).is_some_and(|m| m.class.prefer_box)
    }

    /// The name of the class a label reads as, if any.
    #[must_use]
    pub fn class_name(&self, label: &str) -> Option<&str> {
        self.classify(label).map(|m| m.class.name.as_str())
    }

    /// The joint type a label's motion word names, for a label that names no class (`slider`,
    /// `hinge_2`): what the label says of the part is how it moves.
    #[must_use]
    pub fn motion_without_class(&self, label: &str) -> Option<(String, JointKind)> {
        if self.classify(label).is_some() {
            return None;
        }
        label_tokens(label).find_map(|t| self.motion_words.get(&t).map(|k| (t.clone(), *k)))
    }

    /// Whether a part with this label, mounted on a door or lid, marks its free edge: a grip,
    /// or a class with [`PartClass::marks_free_edge`] (a knob, a latch).
    #[must_use]
    pub fn marks_free_edge(&self, label: &str) -> bool {
        self.classify(label).is_some_and(|m| m.class.role == Role::Grip || m.class.marks_free_edge)
    }

    /// Whether `parent_label`'s class is a typical parent of `child_label`'s class.
    #[must_use]
    pub fn is_typical_parent(&self, child_label: &str, parent_label: &str) -> bool {
        match (self.classify(child_label), self.classify(parent_label)) {
            (Some(c), Some(p)) => c.class.parents.contains(&p.class.name),
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The class, whole-token flag and allowed motion a label is read as.
    fn check(label: &str, expected: Option<(&str, JointKind)>) {
        let vocab = Vocabulary::builtin();
        let got = vocab.classify(label).map(|m| (m.class.name.clone(), vocab.joint_kind(label)));
        assert_eq!(got, expected.map(|(c, k)| (c.to_owned(), k)), "label {label:?}");
    }

    #[test]
    fn the_builtin_vocabulary_parses_and_its_parents_exist() {
        let v = Vocabulary::builtin();
        assert!(v.classes().len() >= 15);
        assert!(v.class("door").is_some_and(|c| c.allows(JointKind::Prismatic)));
    }

    #[test]
    fn labels_of_public_datasets_read_as_their_class_and_motion() {
        use JointKind::{Continuous, Fixed, Prismatic, Revolute};
        check("drawer", Some(("drawer", Prismatic)));
        check("Drawer_2", Some(("drawer", Prismatic)));
        check("door", Some(("door", Revolute)));
        check("door_handle", Some(("handle", Fixed)));
        check("cabinet.door", Some(("door", Revolute)));
        check("lid", Some(("lid", Revolute)));
        check("knob", Some(("knob", Revolute)));
        check("button", Some(("button", Prismatic)));
        check("leg", Some(("leg", Fixed)));
        check("glorp", None);
        // GAPartNet / PartNet-Mobility: the motion word decides when the class allows it.
        check("slider_drawer", Some(("drawer", Prismatic)));
        check("hinge_door", Some(("door", Revolute)));
        check("sliding_door", Some(("door", Prismatic)));
        check("slider_lid", Some(("lid", Prismatic)));
        check("hinge_lid", Some(("lid", Revolute)));
        check("hinge_knob", Some(("knob", Revolute)));
        check("slider_button", Some(("button", Prismatic)));
        check("line_fixed_handle", Some(("handle", Fixed)));
        check("hinge_handle", Some(("handle", Revolute)));
        check("wheel", Some(("wheel", Continuous)));
        check("caster", Some(("wheel", Continuous)));
        check("sash", Some(("sliding_panel", Prismatic)));
        // What is mounted at a door's free edge: grips, knobs, latches; not another door.
        let v = Vocabulary::builtin();
        let marks: Vec<bool> = ["door_handle", "knob", "latch", "lock", "door", "body"].iter().map(|l| v.marks_free_edge(l)).collect();
        assert_eq!(marks, [true, true, true, true, false, false]);
        // Labels of a motion alone move so; rotors spin, blades turn.
        assert_eq!(v.motion_without_class("slider"), Some(("slider".to_owned(), Prismatic)));
        assert_eq!(v.motion_without_class("hinge_2"), Some(("hinge".to_owned(), Revolute)));
        assert_eq!(v.motion_without_class("slider_drawer"), None, "a class decides");
        check("propeller", Some(("rotor", Continuous)));
        check("blade", Some(("blade", Revolute)));
        check("spinning_blade", Some(("blade", Continuous)));
        // A toilet's seat hinges like its lid; a chair's is rigid.
        let seat_in = |category: &str| v.classify_in("seat", category).map(|m| m.class.name.clone());
        assert_eq!(seat_in("Toilet"), Some("lid".to_owned()));
        assert_eq!(seat_in("chair"), Some("seat".to_owned()));
        // A latch turns unless a motion word says its bolt slides.
        check("latch", Some(("latch", Revolute)));
        check("slide_bolt", Some(("latch", Prismatic)));
        check("slide", Some(("sliding_panel", Prismatic)));
        // A motion word the class does not allow is ignored.
        check("hinge_drawer", Some(("drawer", Prismatic)));
        // Compounds: the word ending last; a word inside a longer one does not count.
        check("drawercase", Some(("body", Fixed)));
        check("lightswitchbaseroot", Some(("body", Fixed)));
        check("microdoorroot", Some(("door", Revolute)));
        check("drawer1_top", Some(("drawer", Prismatic)));
        check("sliding", None);
        check("cupboard", Some(("body", Fixed)));
        // A lock is a latch, mounted on what it locks (not a lever on the body).
        check("door_lock", Some(("latch", Revolute)));
        check("lock_link", Some(("latch", Revolute)));
        check("latch", Some(("latch", Revolute)));
    }

    #[test]
    fn a_user_file_overrides_a_class_and_adds_new_ones_first() {
        let extra = Vocabulary::parse(
            r#"
            [motion_words]
            swivel = "continuous"
            [[class]]
            name = "drawer"
            role = "movable"
            joints = ["prismatic"]
            words = ["drawer", "schublade"]
            [[class]]
            name = "propeller"
            role = "movable"
            joints = ["continuous"]
            words = ["propeller", "handle"]
            "#,
            "extra",
        )
        .expect("parses");
        let v = Vocabulary::builtin().extended_with(extra);
        assert_eq!(v.classify("schublade").map(|m| m.class.name.clone()).as_deref(), Some("drawer"));
        assert_eq!(v.classify("handle").map(|m| m.class.name.clone()).as_deref(), Some("propeller"), "new classes first");
        assert_eq!(v.classes().iter().filter(|c| c.name == "drawer").count(), 1);
    }

    #[test]
    fn bad_vocabulary_files_name_the_class_and_what_was_expected() {
        let err = |text: &str| Vocabulary::parse(text, "v.toml").expect_err("refused").to_string();
        let e = err("[[class]]\nname = \"x\"\nrole = \"movable\"\njoints = []\nwords = [\"x\"]\n");
        assert!(e.contains("v.toml") && e.contains("`x`") && e.contains("joints"), "{e}");
        let e = err("[[class]]\nname = \"x\"\nrole = \"movable\"\njoints = [\"fixed\"]\nwords = [\"Door\"]\n");
        assert!(e.contains("lowercase"), "{e}");
        let e = err("[[class]]\nname = \"x\"\nrole = \"spinning\"\njoints = [\"fixed\"]\nwords = [\"x\"]\n");
        assert!(e.contains("v.toml") && e.contains("spinning"), "{e}");
        let e = err("[[class]]\nname = \"x\"\nrole = \"rigid\"\njoints = [\"fixed\"]\nwords = [\"x\"]\nparents = [\"nope\"]\n");
        assert!(e.contains("nope"), "{e}");
    }
}
