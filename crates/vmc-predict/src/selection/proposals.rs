//! Candidate sensor sets proposed by the stated rules (see the module doc of [`super`]):
//! correlation clustering of the candidates into K groups of similar thermal behaviour
//! (agglomerative, average linkage, distance `1 − |r|`), one sensor per cluster chosen by
//! relevance or by greedy forward selection on the linear score; and the linear forward
//! selection itself. Each proposal is ranked by forward selection on the linear score within
//! the set, which gives every sensor its error contribution as evidence.

use super::{pearson, SelectionData};

/// How candidate temperatures are compared when clustering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CorrBasis {
    /// The readings themselves.
    Readings,
    /// Rise above the first reference sensor (ambient): what the machine's own heat sources do,
    /// without the ambient swing every slow node follows.
    Rise,
}

/// Which rule proposed a set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// One sensor per correlation cluster: the one most correlated with a thermal error.
    ClusterRelevance(CorrBasis),
    /// One sensor per correlation cluster, by greedy forward selection on the linear score
    /// (each step adds the sensor, from a cluster not yet covered, that lowers it most).
    ClusterGreedy(CorrBasis),
    /// Greedy forward selection on the linear score (information phase), then coverage
    /// ([`super::Phase`]).
    LinearForward,
}

impl Rule {
    /// Short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Rule::ClusterRelevance(CorrBasis::Readings) => "clusters(readings)+relevance",
            Rule::ClusterRelevance(CorrBasis::Rise) => "clusters(rise)+relevance",
            Rule::ClusterGreedy(CorrBasis::Readings) => "clusters(readings)+greedy",
            Rule::ClusterGreedy(CorrBasis::Rise) => "clusters(rise)+greedy",
            Rule::LinearForward => "linear forward",
        }
    }
}

/// One sensor of a proposal, in rank order.
#[derive(Debug, Clone, PartialEq)]
pub struct RankedSensor {
    /// Candidate name.
    pub name: String,
    /// Index of its cluster in [`Proposal::clusters`] (`None` for the linear forward rule).
    pub cluster: Option<usize>,
    /// Linear score of the reference plus the sensors ranked so far, µm.
    pub score_um: f64,
    /// Score decrease it brought at its rank, µm (its error contribution).
    pub gain_um: f64,
}

/// A candidate set proposed by one rule.
#[derive(Debug, Clone, PartialEq)]
pub struct Proposal {
    /// The rule.
    pub rule: Rule,
    /// Reference sensors, then the others in rank order.
    pub sensors: Vec<String>,
    /// The non-reference sensors in rank order, with their evidence.
    pub ranking: Vec<RankedSensor>,
    /// The clusters the rule picked from (candidate names; empty for the linear forward rule).
    pub clusters: Vec<Vec<String>>,
    /// Linear score of the whole set, µm.
    pub score_um: f64,
}

impl SelectionData {
    /// |r| matrix of `cols` over the densest group's rows; with `reference`, of each column's
    /// difference to that column.
    pub(super) fn abs_corr_matrix(
        &self,
        cols: &[usize],
        reference: Option<usize>,
    ) -> Vec<Vec<f64>> {
        let g = self
            .groups
            .iter()
            .max_by_key(|g| g.temps.nrows())
            .expect("at least one group");
        let series: Vec<Vec<f64>> = cols
            .iter()
            .map(|&c| {
                (0..g.temps.nrows())
                    .map(|i| g.temps[(i, c)] - reference.map_or(0.0, |r| g.temps[(i, r)]))
                    .collect()
            })
            .collect();
        let n = cols.len();
        let mut m = vec![vec![1.0; n]; n];
        for a in 0..n {
            for b in a + 1..n {
                let r = pearson(series[a].iter(), series[b].iter()).abs();
                m[a][b] = r;
                m[b][a] = r;
            }
        }
        m
    }

    /// Forward selection on the linear score within `set`, from `reference`: the ranking.
    fn rank_within(
        &self,
        reference: &[usize],
        set: &[usize],
        cluster_of: &dyn Fn(usize) -> Option<usize>,
    ) -> Vec<(usize, Option<usize>, f64, f64)> {
        let mut chosen = reference.to_vec();
        let mut score = self.score_um(&chosen);
        let mut left: Vec<usize> = set.to_vec();
        let mut out = Vec::new();
        while !left.is_empty() {
            let (k, s) = left
                .iter()
                .enumerate()
                .map(|(k, &i)| {
                    let mut with = chosen.clone();
                    with.push(i);
                    (k, self.score_um(&with))
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .expect("left is not empty");
            let i = left.remove(k);
            chosen.push(i);
            out.push((i, cluster_of(i), s, score - s));
            score = s;
        }
        out
    }
}

/// Average-linkage agglomerative clustering of `sim.len()` items with similarity `sim` (|r|)
/// into `k` clusters (all singletons when there are fewer items). Each cluster lists item
/// indices in ascending order; clusters come in order of their smallest item. Deterministic:
/// of equally similar pairs, the first found merges.
pub(super) fn average_linkage(sim: &[Vec<f64>], k: usize) -> Vec<Vec<usize>> {
    let mut clusters: Vec<Vec<usize>> = (0..sim.len()).map(|i| vec![i]).collect();
    let link = |a: &[usize], b: &[usize]| {
        let s: f64 = a
            .iter()
            .flat_map(|&i| b.iter().map(move |&j| sim[i][j]))
            .sum();
        s / (a.len() * b.len()) as f64
    };
    while clusters.len() > k.max(1) {
        let mut best = (f64::NEG_INFINITY, 0, 1);
        for a in 0..clusters.len() {
            for b in a + 1..clusters.len() {
                let s = link(&clusters[a], &clusters[b]);
                if s > best.0 {
                    best = (s, a, b);
                }
            }
        }
        let (_, a, b) = best;
        let moved = clusters.remove(b);
        clusters[a].extend(moved);
        clusters[a].sort_unstable();
    }
    clusters.sort_by_key(|c| c[0]);
    clusters
}

/// The proposals of every rule. `pool`: candidate columns besides the reference; `relevance`:
/// each column's strongest |r| with a thermal error; `forward`: the linear forward selection's
/// columns in order.
pub(super) fn build(
    data: &SelectionData,
    reference: &[usize],
    pool: &[usize],
    relevance: &[f64],
    forward: &[usize],
    k: usize,
) -> Vec<Proposal> {
    let names = &data.names;
    let finish = |rule: Rule, set: &[usize], clusters: &[Vec<usize>]| {
        let cluster_of = |i: usize| clusters.iter().position(|c| c.contains(&i));
        let ranking: Vec<RankedSensor> = data
            .rank_within(reference, set, &cluster_of)
            .into_iter()
            .map(|(i, cluster, score_um, gain_um)| RankedSensor {
                name: names[i].clone(),
                cluster,
                score_um,
                gain_um,
            })
            .collect();
        Proposal {
            rule,
            sensors: reference
                .iter()
                .map(|&i| names[i].clone())
                .chain(ranking.iter().map(|r| r.name.clone()))
                .collect(),
            score_um: ranking
                .last()
                .map_or_else(|| data.score_um(reference), |r| r.score_um),
            ranking,
            clusters: clusters
                .iter()
                .map(|c| c.iter().map(|&i| names[i].clone()).collect())
                .collect(),
        }
    };
    let mut out = Vec::new();
    for basis in [CorrBasis::Readings, CorrBasis::Rise] {
        let base = match basis {
            CorrBasis::Readings => None,
            CorrBasis::Rise => reference.first().copied(),
        };
        let sim = data.abs_corr_matrix(pool, base);
        let clusters: Vec<Vec<usize>> = average_linkage(&sim, k)
            .into_iter()
            .map(|c| c.into_iter().map(|i| pool[i]).collect())
            .collect();
        // Most relevant member of each cluster.
        let by_relevance: Vec<usize> = clusters
            .iter()
            .map(|c| {
                *c.iter()
                    .max_by(|&&a, &&b| relevance[a].total_cmp(&relevance[b]))
                    .expect("clusters are not empty")
            })
            .collect();
        out.push(finish(
            Rule::ClusterRelevance(basis),
            &by_relevance,
            &clusters,
        ));
        // Greedy forward selection, one sensor per cluster.
        let mut chosen = reference.to_vec();
        let mut left: Vec<&Vec<usize>> = clusters.iter().collect();
        let mut picked = Vec::new();
        while !left.is_empty() {
            let mut best = (f64::INFINITY, 0, left[0][0]);
            for (ci, c) in left.iter().enumerate() {
                for &i in c.iter() {
                    let mut with = chosen.clone();
                    with.push(i);
                    let s = data.score_um(&with);
                    if s < best.0 {
                        best = (s, ci, i);
                    }
                }
            }
            chosen.push(best.2);
            picked.push(best.2);
            left.remove(best.1);
        }
        out.push(finish(Rule::ClusterGreedy(basis), &picked, &clusters));
    }
    out.push(finish(Rule::LinearForward, forward, &[]));
    out
}
