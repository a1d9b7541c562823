//! Integration tests of the event store: one suite run against both backends (SQLite on a
//! temp file, PostgreSQL on the server named by `STANICE_TEST_POSTGRES_URL`, which
//! `scripts/with-postgres.sh` provides), plus backend-specific, recorder and retention
//! tests.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod crash;
mod fixture;
mod partitions;
mod pg;
mod recorder;
mod retention;
mod specific;
mod suite;

/// Generates, for every suite function, a test on SQLite and one on PostgreSQL, each as
/// it is and passing after every append.
macro_rules! on_both_backends {
    ($($name:ident),* $(,)?) => {
        mod sqlite {
            $(
                #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
                async fn $name() {
                    let fx = crate::fixture::sqlite().await;
                    crate::suite::$name(fx.store.clone()).await;
                    fx.finish().await;
                }
            )*
        }
        mod sqlite_segmented {
            $(
                #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
                async fn $name() {
                    let fx = crate::fixture::sqlite_segmented().await;
                    crate::suite::$name(fx.store.clone()).await;
                    fx.finish().await;
                }
            )*
        }
        mod postgres {
            $(
                #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
                async fn $name() {
                    let Some(fx) = crate::fixture::postgres(stringify!($name)).await else {
                        return;
                    };
                    crate::suite::$name(fx.store.clone()).await;
                    fx.finish().await;
                }
            )*
        }
        mod postgres_segmented {
            $(
                #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
                async fn $name() {
                    let Some(fx) = crate::fixture::postgres_segmented(stringify!($name)).await
                    else {
                        return;
                    };
                    crate::suite::$name(fx.store.clone()).await;
                    fx.finish().await;
                }
            )*
        }
    };
}

on_both_backends!(
    round_trip_every_value_cause_and_quality,
    ids_increase_in_batch_order,
    empty_batch_is_a_no_op,
    filters_time_range_by_source_and_received,
    filters_point_exact_and_prefix,
    filters_node_cause_and_invalid,
    ordering_by_event_time,
    pagination_with_equal_timestamps,
    pagination_across_days_and_late_batches,
    pagination_while_appending,
    command_audit_round_trip_and_queries,
    command_pagination,
    purge_by_age,
    purge_goes_by_event_time,
    keyed_events_are_stored_once,
    stats_count_rows,
    batch_of_100k_events,
    concurrent_writers,
    bad_input_is_refused_cleanly,
    lift_faults_round_trip_and_filters,
    lift_faults_every_order_both_directions,
    lift_faults_paging_with_total_and_newest_tail,
    lift_fault_pages_cover_every_row_once,
    lift_fault_bad_input_is_refused,
    notifications_round_trip_and_paging,
    purge_keeps_lift_faults_and_drops_old_notifications,
    trend_downsamples_per_bucket,
    trend_first_and_last_per_bucket,
    trend_reads_the_rollups,
);
